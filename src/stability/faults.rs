//! Case 8: faults. Every device-memory allocation of start-up and
//! streaming is made to fail in turn (the quick form: a spread of them),
//! with the default effects and with every effect a renderer can build
//! (a decal and assets too, `rig::every_effect`), and a lost
//! device is injected at a queue submission and at a fence wait, again
//! with both. Each failure must come back as an error (or the frame go on with
//! less), never a panic; and after it everything is destroyed cleanly: no
//! live Vulkan object, no validation message, on a fresh context per try.

use super::rig::Rig;
use super::{CaseReport, Form};
use crate::error::{Error, Result};
use crate::gpu::{Context, ContextOptions};
use crate::render::RendererOptions;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// The renderers the faults meet: the default effects, and every effect.
fn configurations() -> [(&'static str, RendererOptions); 2] {
    [("default effects", RendererOptions::default()), ("every effect", super::rig::every_effect())]
}

/// What the script does: start the renderer, stream one view until it
/// settles, fly to another and stream that.
fn script(ctx: &Context, options: &RendererOptions, on_start: &mut dyn FnMut()) -> Result<()> {
    let mut rig = Rig::new(ctx, [64, 48], 60, options.clone(), Vec::new())?;
    on_start();
    let a = rig.view(rig.camera(500.0, 500.0, 30.0, 0.0, -30.0));
    rig.settled_shot(ctx, &a)?;
    let b = rig.view(rig.camera(1500.0, 1400.0, 30.0, 90.0, -30.0));
    rig.settled_shot(ctx, &b)?;
    Ok(())
}

/// The outcome of one injected fault, after teardown.
struct Outcome {
    result: std::result::Result<Result<()>, ()>,
    live: i64,
    messages: usize,
}

fn attempt(options: &ContextOptions, arm: &dyn Fn(&Context), f: &dyn Fn(&Context) -> Result<()>) -> Result<Outcome> {
    let ctx = Context::headless(options)?;
    let log = ctx.validation_log();
    arm(&ctx);
    let result = catch_unwind(AssertUnwindSafe(|| f(&ctx))).map_err(|_| ());
    ctx.faults().disarm();
    ctx.wait_idle()?;
    let live = ctx.live_objects().total();
    drop(ctx);
    Ok(Outcome { result, live, messages: log.messages().len() })
}

pub fn run(options: &ContextOptions, form: Form) -> Result<CaseReport> {
    let mut r = CaseReport::new(8, "faults");
    r.measured = "panics, objects left alive, validation messages after an injected allocation failure (each of start-up and the frames) or a lost device at submit / fence wait; frames before a lost device is reported".into();
    r.bound = "0, 0, 0; 0 frames late".into();
    r.why = "a failure the caller cannot prevent must reach them as an error from the call that met it, and dropping what exists must still free everything, so an engine can recover or shut down".into();
    let (mut panics, mut leaks, mut messages) = (0usize, 0i64, 0usize);
    for (name, config) in configurations() {
        let t = allocation_faults(options, form, &config, &mut r, name)?;
        panics += t.0;
        leaks += t.1;
        messages += t.2;
    }
    // A lost device: the frame that submits (or waits) must fail.
    let mut late = 0u32;
    for (name, config) in configurations() {
        for (what, which) in [("submit", 1usize), ("fence wait", 2)] {
            let o = attempt(options, &|_| (), &|ctx| lose_device(ctx, &config, which))?;
            let ok = matches!(o.result, Ok(Ok(())));
            late += u32::from(!ok);
            panics += usize::from(o.result.is_err());
            leaks += o.live;
            messages += o.messages;
            let how = match &o.result {
                Ok(Ok(())) => "the frame that met it returned DeviceLost".to_string(),
                Ok(Err(e)) => format!("WRONG: {e}"),
                Err(()) => "PANIC".into(),
            };
            r.details.push(format!(
                "{name}, device lost at {what}: {how}; then {} objects alive, {} validation messages",
                o.live, o.messages
            ));
        }
    }
    r.worst = format!("{panics}, {leaks}, {messages}; {late} late");
    r.pass = panics == 0 && leaks == 0 && messages == 0 && late == 0;
    Ok(r)
}

/// Every (quick: a spread of) allocation of one configuration failed in
/// turn: (panics, objects left alive, validation messages).
fn allocation_faults(
    options: &ContextOptions,
    form: Form,
    config: &RendererOptions,
    r: &mut CaseReport,
    name: &str,
) -> Result<(usize, i64, usize)> {
    // The clean run: how many allocations start-up and streaming make.
    let mut at_start = 0u64;
    let total = {
        let ctx = Context::headless(options)?;
        let base = ctx.faults().counts()[0];
        script(&ctx, config, &mut || at_start = ctx.faults().counts()[0] - base)?;
        ctx.wait_idle()?;
        ctx.faults().counts()[0] - base
    };
    let indices = fault_indices(form, total, at_start);
    let (mut panics, mut leaks, mut messages, mut errors, mut survived) = (0usize, 0i64, 0usize, 0usize, 0usize);
    for &k in &indices {
        let o = attempt(options, &|ctx| ctx.faults().fail_allocation_in(k), &|ctx| script(ctx, config, &mut || ()))?;
        match &o.result {
            Err(()) => {
                panics += 1;
                r.details.push(format!("{name}, allocation {k}: PANIC"));
            }
            Ok(Err(Error::OutOfDeviceMemory)) => errors += 1,
            Ok(Err(e)) => {
                errors += 1;
                r.details.push(format!("{name}, allocation {k}: error {e}"));
            }
            Ok(Ok(())) => survived += 1,
        }
        leaks += o.live;
        messages += o.messages;
        if o.live != 0 || o.messages != 0 {
            r.details.push(format!(
                "{name}, allocation {k}: {} objects alive, {} validation messages after teardown",
                o.live, o.messages
            ));
        }
    }
    r.details.push(format!(
        "{name}: {} of {total} allocations failed in turn ({at_start} creating the renderer and targets, {} in the frames: the G-buffer and tile lists of the first frame, read-backs; streaming uses slots made at start-up): {errors} returned an error, {survived} went on without it",
        indices.len(),
        total - at_start
    ));
    Ok((panics, leaks, messages))
}

/// The allocations to fail, in turn: every one, or (quick) every start-up
/// allocation up to 8, then a spread, and the last.
fn fault_indices(form: Form, total: u64, at_start: u64) -> Vec<u64> {
    match form {
        Form::Full => (0..total).collect(),
        Form::Quick => {
            let mut v: Vec<u64> = (0..total).step_by((total as usize / 16).max(1)).collect();
            v.extend([at_start.saturating_sub(1), at_start, total - 1]);
            v.sort_unstable();
            v.dedup();
            v
        }
    }
}

/// Renders frames with the device lost at the next submit (`which` 1) or
/// fence wait (2): Ok when the frame that met it returned DeviceLost.
fn lose_device(ctx: &Context, config: &RendererOptions, which: usize) -> Result<()> {
    let mut rig = Rig::new(ctx, [64, 48], 60, config.clone(), Vec::new())?;
    let view = rig.view(rig.camera(500.0, 500.0, 30.0, 0.0, -30.0));
    rig.off.frame(ctx, &mut rig.renderer, &view)?;
    let armed = ctx.faults().counts()[which];
    if which == 1 {
        ctx.faults().lose_device_at_submit_in(0);
    } else {
        ctx.faults().lose_device_at_wait_in(0);
    }
    for frame in 0..8u32 {
        let before = ctx.faults().counts()[which];
        let result = rig.off.frame(ctx, &mut rig.renderer, &view);
        let hit_here = before <= armed && ctx.faults().counts()[which] > armed;
        match result {
            Err(Error::DeviceLost) if hit_here => return Ok(()),
            Err(e) => return Err(e),
            Ok(()) if ctx.faults().counts()[which] > armed => {
                return Err(Error::BadInput(format!("frame {frame} met the lost device and returned Ok")))
            }
            Ok(()) => {}
        }
    }
    Err(Error::BadInput("the injected fault was never met".into()))
}
