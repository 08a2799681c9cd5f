//! How many nodes stay resident: `--gpu-budget MIB` (or the device's
//! default) divided by what one node slot costs the scene's renderer, or
//! `--slots` as given. Checked in the options' terms before Vulkan starts
//! where the device does not matter.

use crate::render_cmd::ViewpointArgs;
use crate::world_args::{check_slots, LoadedWorld};
use anyhow::Result;
use vista::render::LodRule;
use vista::terrain::{default_gpu_budget, max_slots, slots_for_budget};

/// Where the slot count came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Given {
    Slots,
    Budget,
    Default,
}

/// The slots a renderer gets and why.
#[derive(Clone, Copy, Debug)]
pub struct NodeBudget {
    pub slots: u32,
    pub given: Given,
    /// Bytes of GPU memory a resident node costs this scene's renderer.
    pub slot_bytes: u64,
    /// The budget (bytes); for `--slots`, what they cost.
    pub budget_bytes: u64,
    /// The device holds fewer slots than the budget pays for.
    pub capped: bool,
}

const MIB: f64 = (1u64 << 20) as f64;

fn slot_bytes(world: &LoadedWorld, rule: LodRule) -> u64 {
    let source_holes = world.source.has_holes();
    let bytes = vista::render::slot_bytes(world.bake.format, &world.effects, &world.desc, &world.holes, source_holes);
    match rule {
        LodRule::Patch => bytes,
        LodRule::Triangle => bytes + vista::render::vertex_bounds_slot_bytes(),
    }
}

/// Refuses, before Vulkan starts, a slot count or a budget that cannot
/// hold the world's roots (and a budget that is not a positive size).
pub fn check(args: &ViewpointArgs, world: &LoadedWorld) -> Result<()> {
    if let Some(slots) = args.slots {
        return check_slots(slots, &world.desc);
    }
    let Some(mib) = args.gpu_budget else { return Ok(()) };
    if !(mib.is_finite() && mib > 0.0 && mib <= 1e9) {
        return Err(anyhow::Error::new(crate::InputError(format!(
            "--gpu-budget {mib}: a budget is a positive number of MiB"
        ))));
    }
    let per = slot_bytes(world, args.lod_rule);
    let fit = ((mib * MIB) as u64 / per).min(u64::from(vista::terrain::quadtree::MAX_SLOTS)) as u32;
    check_slots(fit.max(1), &world.desc).map_err(|e| {
        let why = e.to_string();
        let why = why.split_once(": ").map_or(why.as_str(), |(_, w)| w);
        anyhow::Error::new(crate::InputError(format!(
            "--gpu-budget {mib} MiB holds {fit} nodes of {:.0} KiB each: {why}",
            per as f64 / 1024.0
        )))
    })
}

/// The slots the default budget buys a renderer of `world` on this device
/// (what `vista bench accuracy` gives its renderers without `--slots`).
pub fn default_slots(world: &LoadedWorld, device: &vista::gpu::Limits) -> Result<u32> {
    let per = slot_bytes(world, LodRule::Patch);
    let slots = slots_for_budget(default_gpu_budget(device, per), per, device);
    check_slots(slots, &world.desc)?;
    Ok(slots)
}

impl NodeBudget {
    /// The slots `args` give a renderer of `world` on this device.
    pub fn of(args: &ViewpointArgs, world: &LoadedWorld, device: &vista::gpu::Limits) -> Result<Self> {
        let slot_bytes = slot_bytes(world, args.lod_rule);
        if let Some(slots) = args.slots {
            let budget_bytes = u64::from(slots) * slot_bytes;
            return Ok(NodeBudget { slots, given: Given::Slots, slot_bytes, budget_bytes, capped: false });
        }
        let (given, budget_bytes) = match args.gpu_budget {
            Some(mib) => (Given::Budget, (mib * MIB) as u64),
            None => (Given::Default, default_gpu_budget(device, slot_bytes)),
        };
        let slots = slots_for_budget(budget_bytes, slot_bytes, device);
        let capped = budget_bytes / slot_bytes > u64::from(max_slots(device));
        check_slots(slots, &world.desc)?;
        Ok(NodeBudget { slots, given, slot_bytes, budget_bytes, capped })
    }

    /// For the `stream:` line: "(GPU budget 128.0 MiB (default), 64 KiB a node)".
    pub fn describe(&self) -> String {
        let from = match self.given {
            Given::Slots => "--slots",
            Given::Budget => "--gpu-budget",
            Given::Default => "default",
        };
        let cap = if self.capped { "; the device's atlases hold no more slots" } else { "" };
        format!(
            "GPU budget {:.1} MiB ({from}), {:.0} KiB a node{cap}",
            self.budget_bytes as f64 / MIB,
            self.slot_bytes as f64 / 1024.0
        )
    }
}
