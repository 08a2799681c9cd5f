//! Every effect vista knows, one line each: adding an effect is its
//! folder and a line here.

use super::kind::EffectKind;
use crate::scene::effect::Effect;

static KINDS: [&dyn EffectKind; Effect::ALL.len()] = [
    &super::core::Holes,
    &super::core::ConeCull,
    &super::core::Occlusion,
    &super::materials::kinds::Cliffs,
    &super::cliff_meshes::kind::CliffMeshesKind,
    &super::materials::kinds::Splat,
    &super::virtual_texture::kind::VirtualTextureKind,
    &super::core::Lighting,
    &super::core::Queries,
    &super::virtual_texture::kind::DecalsKind,
    &super::assets::kind::AssetsKind,
    &super::grass::kind::GrassKind,
    &super::shadows::kind::ShadowsKind,
    &super::atmosphere::kind::AtmosphereKind,
];

/// The kind of `effect`.
pub fn kind_of(effect: Effect) -> &'static dyn EffectKind {
    let kind = KINDS[effect as usize];
    debug_assert_eq!(kind.effect(), effect, "the registry follows Effect::ALL");
    kind
}

/// Every kind, in `Effect::ALL` order.
pub fn kinds() -> &'static [&'static dyn EffectKind] {
    &KINDS
}
