//! The rules of the G-buffer tile shading, from the scene's effects: which
//! flavours a scene can produce, where each applies (view distance, slope)
//! and how stochastic cliffs draw their random numbers. They reach the
//! shaders through the view (`TerrainView.shade_*`); none is a literal in a
//! shader. `shade_rules.glsl` states the rule they parameterise.

use crate::scene::effect::{Effect, MaterialsMode};
use crate::shaders::consts;

/// Flavour bits, in the classification target's order.
pub const FLAVOURS: [(u32, &str); 6] = [
    (consts::FLAVOUR_VIRTUAL_TEXTURE, "virtual_texture"),
    (consts::FLAVOUR_FAR_ATLAS, "far_atlas"),
    (consts::FLAVOUR_NEAR_CLIFF, "near_cliff"),
    (consts::FLAVOUR_FAR_CLIFF, "far_cliff"),
    (consts::FLAVOUR_SPLAT, "splat"),
    (consts::FLAVOUR_CONTROL_MAP, "control_map"),
];

/// A variant's flavours joined by `+` (e.g. `far_atlas+splat`).
pub fn variant_name(bits: u32) -> String {
    let names: Vec<&str> = FLAVOURS.iter().filter(|(b, _)| bits & b != 0).map(|(_, n)| *n).collect();
    if names.is_empty() {
        "none".into()
    } else {
        names.join("+")
    }
}

/// How terrain tiles are shaded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Shading {
    /// One pipeline per tile variant, each drawing only its tiles.
    #[default]
    Tiled,
    /// One pipeline with every flavour the scene allows for every tile; a
    /// pixel branches past the flavours it does not need (an uber-shader).
    OneShader,
    /// One pipeline that evaluates every flavour at every pixel, weighting
    /// the ones it does not need by 0 (no branches: the baseline of the
    /// reference talk).
    OneShaderEveryFlavour,
}

impl Shading {
    pub const ALL: [Shading; 3] = [Shading::Tiled, Shading::OneShader, Shading::OneShaderEveryFlavour];

    pub fn name(self) -> &'static str {
        match self {
            Shading::Tiled => "tiled",
            Shading::OneShader => "one shader (branching)",
            Shading::OneShaderEveryFlavour => "one shader (every flavour)",
        }
    }

    /// The variants to build pipelines for, given the scene's.
    pub fn pipelines(self, rules: &ShadeRules) -> Vec<u32> {
        match self {
            Shading::Tiled => rules.variants(),
            _ => vec![rules.allowed],
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadeRules {
    /// Flavours the scene can produce (far atlas always; splat with the
    /// `splat` effect; near and far cliff with `cliffs`).
    pub allowed: u32,
    /// View depth (m) where the far atlas starts replacing splat, and where
    /// it has replaced it (the blend band hides the line).
    pub far_start_m: f32,
    pub far_end_m: f32,
    /// Slope (degrees) at the middle of the splat-to-cliff band, and the
    /// band's width.
    pub cliff_slope_deg: f32,
    pub cliff_band_deg: f32,
    /// View depth (m) of the near-to-far cliff band.
    pub cliff_split_start_m: f32,
    pub cliff_split_end_m: f32,
    /// The far cliff's second tiling scale (times the material's), reached
    /// at `cliff_split_start_m` times this distance.
    pub far_cliff_scale: f32,
    /// Hashed-noise cell scale (Wyman-McGuire's g: 1 = a cell per pixel).
    pub hash_scale: f32,
    pub hash_seed: u32,
    /// False: cliffs blend every material and projection (the reference).
    pub stochastic: bool,
    /// The control-map flavour's tri-planar tighten factor (seed 004): a
    /// plane is sampled where the normal's component along its axis
    /// exceeds it (0: every plane a normal leans towards).
    pub tighten: f32,
}

impl Default for ShadeRules {
    fn default() -> Self {
        ShadeRules {
            allowed: consts::FLAVOUR_FAR_ATLAS,
            far_start_m: 250.0,
            far_end_m: 400.0,
            cliff_slope_deg: 40.0,
            cliff_band_deg: 8.0,
            cliff_split_start_m: 60.0,
            cliff_split_end_m: 100.0,
            far_cliff_scale: 4.0,
            hash_scale: 1.0,
            hash_seed: 0,
            stochastic: true,
            tighten: DEFAULT_TIGHTEN,
        }
    }
}

/// Seed 004 shows 0.3 and 0.576 (where one plane is left almost
/// everywhere); 0.3 keeps a blend band on every ridge (see `vista bench
/// shade` and tests/control_map.rs for what tightening costs and saves).
pub const DEFAULT_TIGHTEN: f32 = 0.3;

/// The shading flavours an effect may add (none for most): `splat` adds
/// the splat or the control-map flavour, as the scene's materials mode says.
pub fn effect_flavours(effect: Effect) -> u32 {
    match effect {
        Effect::Splat => consts::FLAVOUR_SPLAT | consts::FLAVOUR_CONTROL_MAP | consts::FLAVOUR_VIRTUAL_TEXTURE,
        Effect::VirtualTexture => consts::FLAVOUR_VIRTUAL_TEXTURE,
        Effect::Cliffs => consts::FLAVOUR_NEAR_CLIFF | consts::FLAVOUR_FAR_CLIFF,
        _ => 0,
    }
}

impl ShadeRules {
    /// These rules allowing the flavours of the material effects that are
    /// on (`materials`: which near flavour `splat` builds).
    pub fn allowing(self, materials: MaterialsMode, splat: bool, cliffs: bool) -> ShadeRules {
        let mut allowed = consts::FLAVOUR_FAR_ATLAS;
        if splat {
            allowed |= match materials {
                MaterialsMode::Splat => consts::FLAVOUR_SPLAT,
                MaterialsMode::ControlMap => consts::FLAVOUR_CONTROL_MAP,
            };
        }
        if cliffs {
            allowed |= effect_flavours(Effect::Cliffs);
        }
        ShadeRules { allowed, ..self }
    }

    /// These rules with the virtual-texture flavour in place of splat's
    /// (effect `virtual_texture`: the same material, from cached pages).
    pub fn with_virtual_texture(self) -> ShadeRules {
        let allowed = if self.allowed & consts::FLAVOUR_SPLAT != 0 {
            (self.allowed & !consts::FLAVOUR_SPLAT) | consts::FLAVOUR_VIRTUAL_TEXTURE
        } else {
            self.allowed
        };
        ShadeRules { allowed, ..self }
    }

    /// These rules with `effect`'s flavours taken out (switched off for a
    /// frame: the classification then never picks them).
    pub fn without(self, effect: Effect) -> ShadeRules {
        ShadeRules { allowed: self.allowed & !effect_flavours(effect), ..self }
    }

    /// Every variant a frame can produce: the non-empty subsets of the
    /// allowed flavours (a tile ORs any of them).
    pub fn variants(&self) -> Vec<u32> {
        (1..consts::FLAVOUR_VARIANTS).filter(|v| v & !self.allowed == 0).collect()
    }

    /// Normal z where cliff shading starts and where it is full.
    pub fn slope_normal_z(&self) -> [f32; 2] {
        let lo = (self.cliff_slope_deg - self.cliff_band_deg * 0.5).clamp(0.0, 90.0);
        let hi = (self.cliff_slope_deg + self.cliff_band_deg * 0.5).clamp(0.0, 90.0);
        [lo.to_radians().cos(), hi.to_radians().cos()]
    }

    /// The view's `shade_bands`, `shade_slope`, `shade_flags` and `control`.
    pub fn gpu(&self) -> ([f32; 4], [f32; 4], [u32; 4], [f32; 4]) {
        let [nz0, nz1] = self.slope_normal_z();
        (
            [self.far_start_m, self.far_end_m, self.cliff_split_start_m, self.cliff_split_end_m],
            [nz0, nz1, self.far_cliff_scale, self.hash_scale],
            [self.allowed, self.hash_seed, u32::from(self.stochastic), 0],
            [self.tighten, 0.0, 0.0, 0.0],
        )
    }

    /// Planes of the tightened tri-planar blend at unit normal `n` (1 to 3;
    /// `shade_rules.glsl` `tri_planar_planes`).
    pub fn planes(&self, n: [f32; 3]) -> u32 {
        (n.iter().filter(|c| c.abs() > self.tighten).count() as u32).max(1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variants_are_the_subsets_of_the_allowed_flavours() {
        let far = ShadeRules::default();
        assert_eq!(far.variants(), vec![consts::FLAVOUR_FAR_ATLAS]);
        let all = ShadeRules::default().allowing(MaterialsMode::Splat, true, true);
        assert_eq!(all.variants().len(), 15, "4 flavours: 2^4 - 1 variants");
        assert!(all.variants().iter().all(|v| v & consts::FLAVOUR_VIRTUAL_TEXTURE == 0));
        let vt = all.with_virtual_texture();
        assert_eq!(vt.variants().len(), 15, "the virtual texture replaces splat");
        assert!(vt.variants().iter().all(|v| v & consts::FLAVOUR_SPLAT == 0));
        assert_eq!(vt.without(Effect::Splat).allowed & consts::FLAVOUR_VIRTUAL_TEXTURE, 0, "splat off, its cache too");
        assert_eq!(variant_name(consts::FLAVOUR_FAR_ATLAS | consts::FLAVOUR_SPLAT), "far_atlas+splat");
    }
}
