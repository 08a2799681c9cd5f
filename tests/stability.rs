//! The hard cases of `vista stability` (src/stability/), each run in its
//! quick form under the validation layer; each case states its bound and
//! why in its module doc and in the report it returns, which is printed
//! here so a CI log shows the measured figures.

mod common;

use common::gpu_test;
use vista::stability::{self, CaseReport, Form};

fn check(report: vista::Result<CaseReport>) {
    let r = report.expect("the case ran");
    eprintln!("case {} ({}): worst {} (bound {})", r.case, r.name, r.worst, r.bound);
    for d in &r.details {
        eprintln!("  {d}");
    }
    assert!(r.pass, "case {} failed: {} over {}; {}", r.case, r.worst, r.bound, r.details.join("; "));
}

#[test]
fn case_1_far_from_the_origin() {
    gpu_test(|ctx| check(stability::origin::run(ctx, Form::Quick)));
}

#[test]
fn case_2_depth() {
    gpu_test(|ctx| check(stability::depth::run(ctx, Form::Quick)));
}

#[test]
fn case_5_nan_and_infinity_hygiene() {
    gpu_test(|ctx| check(stability::hygiene::run(ctx, Form::Quick)));
}

#[test]
fn case_6_seams_under_motion() {
    gpu_test(|ctx| check(stability::seams::run(ctx, Form::Quick)));
}

/// The in-process half; tests/cli.rs runs `vista stability --cases 7`,
/// which adds a second process and LP_NUM_THREADS=1.
#[test]
fn case_7_determinism_in_one_process() {
    gpu_test(|ctx| check(stability::determinism::run(ctx, Form::Quick, Vec::new())));
}

#[test]
fn case_11_tiny_and_huge_fov() {
    gpu_test(|ctx| check(stability::fov::run(ctx, Form::Quick)));
}

/// Case 8 makes its own contexts (one per injected fault) and checks each
/// one's teardown itself.
#[test]
fn case_8_faults() {
    check(stability::faults::run(&common::validated(), Form::Quick));
}
