//! Finding an effect's kind in the registry (`KINDS`, in `effects/mod.rs`
//! beside the folders' `mod` lines).

use super::kind::EffectKind;
use super::KINDS;
use crate::scene::effect::Effect;

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
