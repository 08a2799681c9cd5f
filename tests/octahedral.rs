//! Stability case 3 (src/stability/octahedral.rs): GLSL and CPU octahedral
//! encoders agree on a million random unit vectors and the hard ones; the
//! angular error of 8+8-bit codes stays under 1 degree (mean under 0.4):
//! the bounds and their reasons are in the case's module.

mod common;

use common::gpu_test;
use vista::stability::{octahedral, Form};

#[test]
fn gpu_and_cpu_codes_are_identical_and_within_a_degree() {
    gpu_test(|ctx| {
        let r = octahedral::run(ctx, Form::Full).expect("the case ran");
        println!("{}", r.details.join("\n"));
        assert!(r.pass, "{} over {}: {}", r.worst, r.bound, r.details.join("; "));
    });
}
