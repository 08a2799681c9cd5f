//! Bad input fuzzing (stability case 9, src/stability/fuzz.rs): 3000 seeded
//! mutations each of a PNG16 and an EXR height map load or fail with a
//! typed one-line error, nothing panics, peak memory stays under the
//! case's bound. Nightly: `VISTA_FUZZ_CASES=200000 cargo test --release
//! --test fuzz_inputs` (or `vista stability --full --cases 9`).

use vista::stability::{fuzz, Form};

#[test]
fn mutated_height_maps_load_or_fail_with_a_typed_error() {
    let r = fuzz::run(Form::Quick).expect("the case ran");
    println!("{}", r.details.join("\n"));
    assert!(r.pass, "{} over {}: {}", r.worst, r.bound, r.details.join("; "));
}
