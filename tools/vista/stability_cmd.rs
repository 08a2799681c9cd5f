//! `vista stability`: runs the hard cases of `vista::stability` under the
//! validation layer, each on a fresh context (so its messages and leaks are
//! its own), and prints the table; exits non-zero when a case fails.

use anyhow::{bail, Context as _, Result};
use clap::Args;
use std::path::PathBuf;
use vista::gpu::{Context, ContextOptions};
use vista::stability::{self, determinism, CaseReport, Form};

#[derive(Args, Debug)]
pub struct StabilityArgs {
    /// Write the table (and every case's details) as JSON.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// The full form (nightly): more frames, vectors and mutations; the soak
    /// (case 10) runs 10 000 frames instead of 1000.
    #[arg(long)]
    pub full: bool,
    /// Run only these cases, e.g. 1,2,7 [default: all eleven].
    #[arg(long, value_delimiter = ',', value_name = "N,...", value_parser = crate::numbers::whole_u8, allow_negative_numbers = true)]
    pub cases: Option<Vec<u8>>,
    /// Soak: sample every N frames [default: 100 quick, 1000 full].
    #[arg(long, value_name = "N", value_parser = crate::numbers::whole_u32, allow_negative_numbers = true)]
    pub soak_every: Option<u32>,
    /// Internal: print the determinism script's frame hashes and exit (the
    /// second process of case 7).
    #[arg(long, hide = true)]
    pub script_hashes: bool,
}

const ALL: [u8; 11] = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11];

pub fn stability(device: Option<String>, args: &StabilityArgs) -> Result<()> {
    let options = ContextOptions { validation: true, device_name: device, ..Default::default() };
    if args.script_hashes {
        let ctx = Context::headless(&options).context("creating the Vulkan context")?;
        let (hashes, _) = determinism::script_hashes(&ctx)?;
        println!("{}", serde_json::to_string(&hashes)?);
        return Ok(());
    }
    if let Some(json) = &args.json {
        crate::out_path::check_out_file(json, "--json")?;
    }
    let cases = args.cases.clone().unwrap_or(ALL.to_vec());
    if let Some(bad) = cases.iter().find(|c| !ALL.contains(c)) {
        return Err(anyhow::Error::new(crate::InputError(format!(
            "--cases: there is no case {bad}; the cases are 1..=11"
        ))));
    }
    if args.soak_every == Some(0) {
        return Err(anyhow::Error::new(crate::InputError("--soak-every must be at least 1".into())));
    }
    let form = if args.full { Form::Full } else { Form::Quick };
    let mut reports = Vec::new();
    let mut device_name = String::new();
    for &case in &cases {
        let start = std::time::Instant::now();
        eprintln!("case {case} ...");
        let mut report = run_case(case, form, &options, args, &mut device_name)?;
        report.details.push(format!("ran in {:.1} s", start.elapsed().as_secs_f64()));
        reports.push(report);
    }
    print_table(&reports, &device_name, form);
    if let Some(path) = &args.json {
        let json = serde_json::json!({
            "device": device_name,
            "form": if args.full { "full" } else { "quick" },
            "cases": reports,
        });
        vista::output::write(path, serde_json::to_string_pretty(&json)?.as_bytes())?;
    }
    let failed: Vec<String> = reports.iter().filter(|r| !r.pass).map(|r| r.case.to_string()).collect();
    if !failed.is_empty() {
        bail!("{} of {} cases failed: {}", failed.len(), reports.len(), failed.join(", "));
    }
    Ok(())
}

/// One case on a fresh validated context; its validation messages and any
/// object left alive after it make it fail.
fn run_case(
    case: u8,
    form: Form,
    options: &ContextOptions,
    args: &StabilityArgs,
    device_name: &mut String,
) -> Result<CaseReport> {
    if case == 9 {
        return Ok(stability::fuzz::run(form)?);
    }
    let ctx = Context::headless(options).context("creating the Vulkan context (the validation layer is required)")?;
    *device_name = ctx.info().name.clone();
    let log = ctx.validation_log();
    let mut report = match case {
        1 => stability::origin::run(&ctx, form)?,
        2 => stability::depth::run(&ctx, form)?,
        3 => stability::octahedral::run(&ctx, form)?,
        4 => stability::grazing::run(&ctx, form)?,
        5 => stability::hygiene::run(&ctx, form)?,
        6 => stability::seams::run(&ctx, form)?,
        7 => stability::determinism::run(&ctx, form, other_processes())?,
        8 => stability::faults::run(options, form)?,
        10 => stability::soak::run(&ctx, form, args.soak_every.unwrap_or(form.pick(100, 1000)), |s| {
            eprintln!(
                "  soak frame {}: {} messages, {} live objects, {} bytes allocated, {:.1} MiB resident",
                s.frame, s.validation_messages, s.live_objects, s.allocated_bytes, s.rss_mib
            )
        })?,
        11 => stability::fov::run(&ctx, form)?,
        _ => unreachable!("checked against ALL"),
    };
    ctx.wait_idle()?;
    let live = ctx.live_objects().total();
    drop(ctx);
    let messages = log.messages();
    if live != 0 || !messages.is_empty() {
        report.pass = false;
        report
            .details
            .push(format!("after the case: {live} Vulkan objects alive, {} validation messages", messages.len()));
        if let Some(m) = messages.first() {
            report.details.push(format!("first message: [{}] {}", m.id_name, m.text));
        }
    }
    Ok(report)
}

/// Case 7's other runs: this binary again, as is and with LP_NUM_THREADS=1
/// (lavapipe's rasteriser threads; other drivers ignore it).
fn other_processes() -> determinism::Runs {
    let run = |threads: Option<&str>| -> vista::Result<Vec<u64>> {
        let fail = |m: String| vista::Error::BadInput(m);
        let exe = std::env::current_exe().map_err(|e| fail(format!("finding this executable: {e}")))?;
        let mut cmd = std::process::Command::new(exe);
        cmd.args(["stability", "--script-hashes"]);
        if let Some(t) = threads {
            cmd.env("LP_NUM_THREADS", t);
        }
        let out = cmd.output().map_err(|e| fail(format!("starting the second process: {e}")))?;
        if !out.status.success() {
            return Err(fail(format!("the second process failed: {}", String::from_utf8_lossy(&out.stderr).trim())));
        }
        serde_json::from_slice(&out.stdout).map_err(|e| fail(format!("the second process printed no hashes: {e}")))
    };
    vec![("a second process".into(), run(None)), ("a second process with LP_NUM_THREADS=1".into(), run(Some("1")))]
}

fn print_table(reports: &[CaseReport], device: &str, form: Form) {
    let form = if form == Form::Full { "full" } else { "quick" };
    println!("vista stability ({form} form) on {device}, each case under the Khronos validation layer");
    println!();
    println!("| case | what | worst measured | bound | result |");
    println!("|---|---|---|---|---|");
    for r in reports {
        let result = if r.pass { "pass" } else { "FAIL" };
        println!("| {} {} | {} | {} | {} | {result} |", r.case, r.name, r.measured, r.worst, r.bound);
    }
    println!();
    for r in reports {
        println!("case {} ({}): why this bound: {}", r.case, r.name, r.why);
        for d in &r.details {
            println!("    {d}");
        }
    }
}
