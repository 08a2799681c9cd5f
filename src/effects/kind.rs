//! The scene side of an effect: its name, its parameters and when it can
//! run. One [`EffectKind`] per [`Effect`], listed in the registry
//! (`KINDS` in `effects/mod.rs`); the scene parser and the decisions read effects only
//! through it.

use super::frame_effect::{BuildInputs, FrameEffect};
use super::requested::Effects;
use crate::error::Result;
use crate::scene::effect::Effect;
use crate::scene::graph::EffectPass;
use std::path::Path;

/// What the world holds that effects need; `None` when it has the data,
/// else why not.
#[derive(Debug, Clone, Default)]
pub struct WorldContent {
    pub holes_missing: Option<String>,
    pub holes_present: String,
    /// Decals given to the renderer.
    pub decals: usize,
    /// Assets given to the renderer (effect assets).
    pub assets: usize,
    /// Output `gbuffer`: the engine lights the frame, so vista's lighting
    /// effects have nothing to change.
    pub engine_lights: bool,
}

/// What an effect asked for becomes, besides "on" (`requested`).
pub enum Verdict {
    On,
    /// On, with what it works from (`requested: {note}`).
    OnWith(String),
    /// Kept on by a test's override although the world lacks its data.
    Forced(String),
    /// Off: why (`requested, but {why}`).
    Off(String),
}

/// One effect as a scene names it.
pub trait EffectKind: Sync {
    fn effect(&self) -> Effect;

    /// Parameters its table may give besides `enabled`.
    fn parameters(&self) -> &'static [&'static str] {
        &[]
    }

    /// Reads one of [`Self::parameters`] (`key`: its full name for errors,
    /// `base`: the scene file's folder).
    fn read(&self, fx: &mut Effects, key: &str, name: &str, v: &toml::Value, base: &Path) -> Result<()> {
        let _ = (fx, v, base);
        unreachable!("{key}: {name} is in the parameter list but not read")
    }

    /// Checks the parameters together, once its table is read.
    fn validate(&self, fx: &Effects) -> Result<()> {
        let _ = fx;
        Ok(())
    }

    /// Requested, whether it can run in this scene and world; `force`
    /// (tests) keeps it on although the world lacks its data.
    fn verdict(&self, fx: &Effects, content: &WorldContent, force: bool) -> Verdict {
        let _ = (fx, content, force);
        Verdict::On
    }

    /// GPU bytes it keeps for every resident node slot (a layer of its
    /// own atlas per slot): a GPU budget pays for them beside the node
    /// payloads.
    fn slot_bytes(&self, fx: &Effects) -> u64 {
        let _ = fx;
        0
    }

    /// The passes it records, each at its point of the frame (the pass
    /// graph's entries: a pass of an effect that is off is not built).
    fn passes(&self) -> &'static [EffectPass] {
        &[]
    }

    /// Its built side when it is on (None: nothing to build, or built
    /// by another kind of its folder).
    fn build(&self, b: &mut BuildInputs) -> Result<Option<Box<dyn FrameEffect>>> {
        let _ = b;
        Ok(None)
    }

    /// Effects that must end up on for it to run, and why.
    fn needs(&self) -> &'static [(Effect, &'static str)] {
        &[]
    }
}
