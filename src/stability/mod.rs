//! The hard cases, each a named measurement with a bound (issue [I]):
//! `vista stability` runs them and prints the table; the tests run the
//! same functions and assert `pass`. Every case returns what it measured,
//! the worst value, the bound and why the bound is what it is, so a failure
//! reads as a number, not a panic.

use serde::Serialize;

pub mod depth;
pub mod determinism;
pub mod faults;
pub mod fov;
pub mod fuzz;
pub mod grazing;
pub mod hygiene;
pub mod octahedral;
pub mod origin;
pub mod rig;
pub mod seams;
pub mod soak;

/// How long a case runs: the quick form (the test suite, the default of
/// `vista stability`) or the full form (`--full`, nightly).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Form {
    Quick,
    Full,
}

impl Form {
    /// `quick` in the quick form, `full` in the full form.
    pub fn pick<T>(self, quick: T, full: T) -> T {
        match self {
            Form::Quick => quick,
            Form::Full => full,
        }
    }
}

/// One row of the stability table.
#[derive(Debug, Clone, Serialize)]
pub struct CaseReport {
    /// The case number (1..=10 from the stability issue, 11 tiny and huge fov).
    pub case: u8,
    /// Short name: "far from the origin", "depth", ...
    pub name: &'static str,
    /// What is measured, in a few words.
    pub measured: String,
    /// The bound, with its unit.
    pub bound: String,
    /// Why the bound is what it is.
    pub why: String,
    /// The worst value measured, with its unit.
    pub worst: String,
    pub pass: bool,
    /// Supporting lines (per sub-case figures), printed under the table.
    pub details: Vec<String>,
}

impl CaseReport {
    pub fn new(case: u8, name: &'static str) -> Self {
        CaseReport {
            case,
            name,
            measured: String::new(),
            bound: String::new(),
            why: String::new(),
            worst: String::new(),
            pass: false,
            details: Vec::new(),
        }
    }
}
