//! A fixed-seed batch of random valid cases (`mpm_lab::random_cases`), run
//! under the contract every case must keep (`mpm_lab::contract`): it
//! finishes, or fails with the solver's error naming its step and cause;
//! never a panic, a refused case, a non-finite number or a broken point in
//! a finished step, or a run past its time limit. The larger batch, with
//! its table by class, is `mpm study robustness` (docs/study/robustness).

use mpm_lab::contract::Outcome;
use mpm_lab::robustness_study::{SEED, detail, run_batch};

/// The first cases of the study's batch: about a minute in the test
/// profile.
const CASES: usize = 150;

#[test]
fn a_fixed_batch_of_random_cases_keeps_the_contract_and_finishes() {
    let entries = run_batch(SEED, CASES);
    let broken: Vec<String> = (entries.iter())
        .filter(|e| !e.tried.outcome.kept())
        .map(|e| {
            format!(
                "{}: {} ({})",
                e.drawn.label(),
                e.tried.outcome.name(),
                detail(&e.tried.outcome)
            )
        })
        .collect();
    assert!(
        broken.is_empty(),
        "the contract broken:\n{}",
        broken.join("\n")
    );
    // The classes held to finishing: the smooth bases (GIMP and the
    // B-splines), at any number of points a cell. The bilinear basis is
    // held to the contract only (docs/study/robustness says why).
    let held: Vec<_> = (entries.iter())
        .filter(|e| e.drawn.basis != "linear")
        .collect();
    let unfinished: Vec<String> = (held.iter())
        .filter(|e| e.tried.outcome != Outcome::Finished)
        .map(|e| format!("{}: {}", e.drawn.label(), detail(&e.tried.outcome)))
        .collect();
    let finished = held.len() - unfinished.len();
    eprintln!(
        "{finished} of {} held cases finished; {} of {CASES} in all",
        held.len(),
        entries
            .iter()
            .filter(|e| e.tried.outcome == Outcome::Finished)
            .count()
    );
    assert!(held.len() >= CASES / 2, "{} held cases", held.len());
    // At least 99%: with this batch's size, every one.
    assert!(
        100 * finished >= 99 * held.len(),
        "{finished} of {} finished:\n{}",
        held.len(),
        unfinished.join("\n")
    );
}
