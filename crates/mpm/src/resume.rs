//! Taking a run's checkpoint between load steps, and restoring one into a
//! simulation built from the same case (what a checkpoint holds, and its
//! encoding: `checkpoint.rs`).

use nalgebra::{Matrix2, Matrix3};

use crate::checkpoint::{
    ArcControlState, Checkpoint, CheckpointError, FORMAT, HistoryState, IncrementState, LoopState,
    SOLID_FORMAT, SolidCheckpoint, StepSizeState,
};
use crate::material::CauchyStress;
use crate::particles::Dim;
use crate::report::Settled;
use crate::stepper::{ArcState, LastIncrement, RunSpace, Simulation, StepSize};
use crate::strength_reduction::{Failed, ReductionState};

impl LastIncrement {
    fn state(&self) -> IncrementState {
        (self.nodes.clone(), self.u.clone(), self.dlambda)
    }
}

impl From<IncrementState> for LastIncrement {
    fn from((nodes, u, dlambda): IncrementState) -> Self {
        Self { nodes, u, dlambda }
    }
}

impl<const D: usize> Simulation<D>
where
    Dim<D>: RunSpace<D>,
{
    /// Load steps converged so far.
    pub fn steps_done(&self) -> usize {
        self.steps_done
    }

    fn step_size_state(&self) -> StepSizeState {
        StepSizeState {
            size: self.step_size.size,
            easy_in_a_row: self.step_size.easy_in_a_row,
            clean_steps: self.step_size.clean_steps,
            wait: self.step_size.wait,
        }
    }

    /// Puts back the step-size control, Newton's predictor, what the last
    /// step reported and the steps done.
    fn restore_controls(
        &mut self,
        s: &StepSizeState,
        last_increment: &Option<IncrementState>,
        settled: &Option<Settled>,
        steps_done: usize,
    ) {
        self.step_size = StepSize {
            size: s.size,
            easy_in_a_row: s.easy_in_a_row,
            clean_steps: s.clean_steps,
            wait: s.wait,
        };
        self.last_increment = last_increment.clone().map(LastIncrement::from);
        self.settled.clone_from(settled);
        self.steps_done = steps_done;
        self.analysed = None;
    }

    /// FNV-1a over what a case fixes before any step: the load steps, the
    /// seeded points (reference positions, volumes, bodies), the supports'
    /// anchors and the probes' reference positions.
    fn fingerprint(&self) -> u64 {
        let mut hash = Fnv::default();
        hash.add(self.load_steps as u64);
        hash.add(self.points.len() as u64);
        for (x, v) in self.points.reference.iter().zip(&self.points.volume0) {
            for c in x {
                hash.add(c.to_bits());
            }
            hash.add(v.to_bits());
        }
        for m in &self.points.material {
            hash.add(u64::from(*m));
        }
        hash.add(self.first_stage_anchors as u64);
        if !self.surface_anchors.is_empty() {
            hash.add(self.surface_anchors.len() as u64);
        }
        if self.stages.len() > 1 {
            for stage in &self.stages {
                hash.add(stage.load_steps as u64);
            }
        }
        for x in &self.probes.reference {
            for c in x {
                hash.add(c.to_bits());
            }
        }
        hash.0
    }
}

impl Simulation<3> {
    /// A 3D run's state now, after [`Simulation::steps_done`] load steps.
    pub fn checkpoint(&self) -> SolidCheckpoint {
        let p = &self.points;
        let columns = |m: &Matrix3<f64>| -> [f64; 9] { m.as_slice().try_into().expect("3x3") };
        SolidCheckpoint {
            format: SOLID_FORMAT,
            fingerprint: self.fingerprint(),
            steps_done: self.steps_done,
            position: p.position.clone(),
            deformation: p.deformation.iter().map(columns).collect(),
            history: (p.history.iter())
                .map(|h| (columns(&h.tensor), h.plastic_strain))
                .collect(),
            yielding: p.yielding.clone(),
            stress: p.stress.iter().map(columns).collect(),
            fbar_pressure: p.fbar_pressure.clone(),
            cell_mean_stress: p.cell_mean_stress.iter().map(columns).collect(),
            step_size: self.step_size_state(),
            last_increment: self.last_increment.as_ref().map(LastIncrement::state),
            settled: self.settled.clone(),
            surface_anchors_moved: self.surface_anchors.iter().map(|a| a.moved()).collect(),
        }
    }

    /// Puts a 3D run back where `checkpoint` was taken. `self` must be
    /// built from the same case and not yet have run; nothing changes on
    /// error.
    pub fn restore(&mut self, checkpoint: &SolidCheckpoint) -> Result<(), CheckpointError> {
        let c = checkpoint;
        if c.fingerprint != self.fingerprint() {
            return Err(CheckpointError::OtherCase(
                "the seeded points or load steps",
            ));
        }
        let n = self.points.len();
        let lengths = [
            c.position.len(),
            c.deformation.len(),
            c.history.len(),
            c.yielding.len(),
            c.stress.len(),
        ];
        let carried = [c.fbar_pressure.len(), c.cell_mean_stress.len()];
        if lengths.iter().any(|&l| l != n) || carried.iter().any(|&l| l != 0 && l != n) {
            return Err(CheckpointError::OtherCase("the material point counts"));
        }
        if c.surface_anchors_moved.len() != self.surface_anchors.len() {
            return Err(CheckpointError::OtherCase("the surface supports"));
        }
        if c.steps_done > self.load_steps {
            return Err(CheckpointError::Unreadable(
                "it is past the case's last load step".into(),
            ));
        }
        let p = &mut self.points;
        p.position.clone_from(&c.position);
        p.fbar_pressure.clone_from(&c.fbar_pressure);
        p.cell_mean_stress = (c.cell_mean_stress.iter())
            .map(|s| Matrix3::from_column_slice(s))
            .collect();
        for (f, s) in p.deformation.iter_mut().zip(&c.deformation) {
            f.copy_from_slice(s);
        }
        for (h, (tensor, plastic_strain)) in p.history.iter_mut().zip(&c.history) {
            h.tensor.copy_from_slice(tensor);
            h.plastic_strain = *plastic_strain;
        }
        p.yielding.clone_from(&c.yielding);
        for (s, saved) in p.stress.iter_mut().zip(&c.stress) {
            s.copy_from_slice(saved);
        }
        for (a, moved) in self
            .surface_anchors
            .iter_mut()
            .zip(&c.surface_anchors_moved)
        {
            a.set_moved(*moved);
        }
        self.restore_controls(&c.step_size, &c.last_increment, &c.settled, c.steps_done);
        Ok(())
    }
}

impl Simulation {
    /// The run's state now, after [`Simulation::steps_done`] load steps.
    pub fn checkpoint(&self) -> Checkpoint {
        let p = &self.points;
        Checkpoint {
            format: FORMAT,
            fingerprint: self.fingerprint(),
            steps_done: self.steps_done,
            position: p.position.clone(),
            deformation: p
                .deformation
                .iter()
                .map(|f| f.as_slice().try_into().expect("2x2"))
                .collect(),
            history: p
                .history
                .iter()
                .map(|h| HistoryState {
                    tensor: h.tensor.as_slice().try_into().expect("2x2"),
                    zz: h.zz,
                    plastic_strain: h.plastic_strain,
                })
                .collect(),
            yielding: p.yielding.clone(),
            stress: p
                .stress
                .iter()
                .map(|s| [s.plane[0], s.plane[1], s.plane[2], s.zz])
                .collect(),
            stress_slopes: (p.stress_slopes.iter().enumerate())
                .filter(|(_, s)| s.iter().any(|&x| x != 0.0))
                .map(|(k, &s)| (k as u32, s))
                .collect(),
            fbar_pressure: p.fbar_pressure.clone(),
            cell_mean_stress: (p.cell_mean_stress.iter())
                .map(|s| s.as_slice().try_into().expect("2x2"))
                .collect(),
            probes: self.probes.position.clone(),
            anchors_moved: self.anchors.iter().map(|a| a.moved()).collect(),
            loops: self.loops.iter().map(LoopState::of).collect(),
            step_size: self.step_size_state(),
            arc: self.arc.as_ref().map(|a| ArcControlState {
                arc: [a.length, a.first_length, a.load_factor],
                easy_in_a_row: a.easy_in_a_row,
                last: a.last.as_ref().map(LastIncrement::state),
            }),
            last_increment: self.last_increment.as_ref().map(LastIncrement::state),
            reduction: self.reduction.as_ref().map(|r| {
                let failed = r.failed.map(|f| [f.factor, f.tried_from]);
                (r.held, failed, [r.scale, r.travelled])
            }),
            settled: self.settled.clone(),
        }
    }

    /// Puts the run back where `checkpoint` was taken. `self` must be built
    /// from the same case and not yet have run; nothing changes on error.
    pub fn restore(&mut self, checkpoint: &Checkpoint) -> Result<(), CheckpointError> {
        let c = checkpoint;
        let n = self.points.len();
        if c.fingerprint != self.fingerprint() {
            return Err(CheckpointError::OtherCase(
                "the seeded points, load steps, supports or probes",
            ));
        }
        let lengths = [
            c.position.len(),
            c.deformation.len(),
            c.history.len(),
            c.yielding.len(),
            c.stress.len(),
        ];
        if lengths.iter().any(|&l| l != n)
            || c.stress_slopes.iter().any(|&(p, _)| p as usize >= n)
            || !(c.fbar_pressure.is_empty() || c.fbar_pressure.len() == n)
            || !(c.cell_mean_stress.is_empty() || c.cell_mean_stress.len() == n)
        {
            return Err(CheckpointError::OtherCase("the material point counts"));
        }
        if c.steps_done > self.load_steps {
            return Err(CheckpointError::Unreadable(
                "it is past the case's last load step".into(),
            ));
        }
        // The anchors are those of the stage of the last step done (a
        // released support's are gone); that stage's loads and supports
        // follow from the case. A fresh simulation is in the first.
        let mut staged = self.anchors.clone();
        let (stage, _) = crate::stages::stage_of(&self.stages, c.steps_done.max(1));
        for k in 1..=stage {
            crate::boundary::ibm::enter_stage(&mut staged, &self.stages[k].ibm);
        }
        if c.probes.len() != self.probes.position.len() || c.anchors_moved.len() != staged.len() {
            return Err(CheckpointError::OtherCase("the probe or anchor counts"));
        }
        // The loops are found once, before any step; anchors and boundary
        // loads refer to them by loop and segment. A checkpoint whose loops
        // differ was written by a solver that finds them differently.
        if c.loops != self.loops.iter().map(LoopState::of).collect::<Vec<_>>() {
            return Err(CheckpointError::OtherCase("the boundary loops"));
        }
        let p = &mut self.points;
        p.position.clone_from(&c.position);
        for (f, s) in p.deformation.iter_mut().zip(&c.deformation) {
            f.copy_from_slice(s);
        }
        for (h, s) in p.history.iter_mut().zip(&c.history) {
            h.tensor.copy_from_slice(&s.tensor);
            h.zz = s.zz;
            h.plastic_strain = s.plastic_strain;
        }
        p.yielding.clone_from(&c.yielding);
        p.stress_slopes.fill([0.0; 6]);
        for &(k, s) in &c.stress_slopes {
            p.stress_slopes[k as usize] = s;
        }
        p.fbar_pressure.clone_from(&c.fbar_pressure);
        p.cell_mean_stress = (c.cell_mean_stress.iter())
            .map(|s| Matrix2::from_column_slice(s))
            .collect();
        p.stress = c
            .stress
            .iter()
            .map(|s| CauchyStress {
                plane: [s[0], s[1], s[2]],
                zz: s[3],
            })
            .collect();
        self.probes.position.clone_from(&c.probes);
        self.anchors = staged;
        self.stage = stage;
        for (a, moved) in self.anchors.iter_mut().zip(&c.anchors_moved) {
            a.set_moved(*moved);
        }
        self.arc = c.arc.as_ref().map(|a| {
            let [length, first_length, load_factor] = a.arc;
            ArcState {
                length,
                first_length,
                load_factor,
                easy_in_a_row: a.easy_in_a_row,
                last: a.last.clone().map(LastIncrement::from),
            }
        });
        // The materials are the case's in a fresh simulation; the
        // reduction's own are those at the factor that last held.
        self.reduction = c
            .reduction
            .map(|(held, failed, [scale, travelled])| ReductionState {
                base: self.points.materials.clone(),
                held,
                failed: failed.map(|[factor, tried_from]| Failed { factor, tried_from }),
                scale,
                travelled,
            });
        if let Some(r) = &self.reduction {
            self.points.materials = r.materials_at(r.held);
        }
        self.restore_controls(&c.step_size, &c.last_increment, &c.settled, c.steps_done);
        Ok(())
    }
}

struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    fn add(&mut self, word: u64) {
        for byte in word.to_le_bytes() {
            self.0 = (self.0 ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Case, Observer, RunReport, SolidStepState, SolveError, StepReport, StepState};

    /// Takes a checkpoint after step `stop_after` and stops the run there,
    /// as a killed worker would (a kill between steps loses at most the
    /// step in progress, which the resumed run solves again).
    struct StopAfter {
        stop_after: usize,
        taken: Option<Vec<u8>>,
    }

    impl Observer for StopAfter {
        fn step_finished(&mut self, report: &StepReport, state: &StepState<'_>) {
            if report.step == self.stop_after {
                self.taken = Some(state.checkpoint().to_bytes());
            }
        }
        fn should_cancel(&mut self) -> bool {
            self.taken.is_some()
        }
    }

    /// The built-in 3D column (40 steps, its points crossing cells), with
    /// and without F-bar and the cell mean (whose points carry their
    /// pressures and stresses across the grid's reset in the checkpoint), stopped after step 20 and resumed from its checkpoint in a fresh
    /// simulation ends where the straight run ends, in the same Newton
    /// iterations; a plane-strain checkpoint is not read as a 3D one.
    #[test]
    fn a_resumed_3d_run_ends_where_the_straight_run_ends() {
        struct StopSolid(Option<Vec<u8>>);
        impl Observer for StopSolid {
            fn solid_step_finished(&mut self, report: &StepReport, state: &SolidStepState<'_>) {
                if report.step == 20 {
                    self.0 = Some(state.checkpoint().to_bytes());
                }
            }
            fn should_cancel(&mut self) -> bool {
                self.0.is_some()
            }
        }
        let text = crate::case::builtin::get("column3d").unwrap();
        for volumetric in ["standard", "fbar", "cell_mean"] {
            let mut case: serde_json::Value = serde_json::from_str(text).unwrap();
            case["analysis"]["volumetric"] = volumetric.into();
            // The default hourglass stiffness (1e-2) lets a point of this
            // column invert at step 20 (in 2D at step 29).
            case["analysis"]["stabilisation"] = serde_json::json!({ "hourglass": 0.05 });
            let case = crate::case::solid::SolidCase::from_json(&case.to_string()).unwrap();
            let mut straight = Simulation::from_solid_case(&case).unwrap();
            let whole = straight.run(&mut crate::NoObserver).unwrap();
            let mut first = Simulation::from_solid_case(&case).unwrap();
            let mut stop = StopSolid(None);
            assert!(matches!(
                first.run(&mut stop),
                Err(SolveError::Cancelled { .. })
            ));
            let bytes = stop.0.expect("a checkpoint after step 20");
            assert!(Checkpoint::from_bytes(&bytes).is_err());
            let checkpoint = SolidCheckpoint::from_bytes(&bytes).unwrap();
            assert_eq!(checkpoint.steps_done(), 20);
            let mut resumed = Simulation::from_solid_case(&case).unwrap();
            resumed.restore(&checkpoint).unwrap();
            let rest = resumed.run(&mut crate::NoObserver).unwrap();
            assert_eq!(rest.steps.len(), 20);
            for (a, b) in rest.steps.iter().zip(&whole.steps[20..]) {
                assert_eq!((a.step, a.newton.iterations), (b.step, b.newton.iterations));
            }
            let moved = (resumed.points.position.iter())
                .zip(&straight.points.position)
                .flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).abs()))
                .fold(0.0, f64::max);
            assert!(moved <= 1e-12 * 50.0, "positions differ by {moved:e}");
            let stressed = (resumed.points.stress.iter())
                .zip(&straight.points.stress)
                .map(|(a, b)| (a - b).abs().max())
                .fold(0.0, f64::max);
            assert!(stressed <= 1e-12 * 4.0e4, "stresses differ by {stressed:e}");
            let carried = match volumetric {
                "fbar" => checkpoint.fbar_pressure.len(),
                "cell_mean" => checkpoint.cell_mean_stress.len(),
                _ => resumed.points.len(),
            };
            assert_eq!(carried, resumed.points.len());
        }
        // A plane-strain case's checkpoint is refused by a 3D run.
        let plane = Simulation::new(&footing()).unwrap().checkpoint().to_bytes();
        assert!(SolidCheckpoint::from_bytes(&plane).is_err());
    }

    fn footing() -> Case {
        Case::from_json(crate::case::builtin::get("footing").unwrap()).unwrap()
    }

    /// The footing example (von Mises flow under an IBM-pushed footing,
    /// F-bar, load steps cut and grown back) stopped after step 4 and
    /// resumed from its checkpoint in a fresh simulation ends where the
    /// straight run ends, with the same Newton iterations and cuts in every
    /// resumed step: the step-size control is part of the state.
    #[test]
    fn a_resumed_run_ends_where_the_straight_run_ends() {
        resumes_where_the_straight_run_ends(footing());
    }

    /// The same with the cell-mean strain, whose carried stresses are
    /// state too.
    #[test]
    fn a_resumed_cell_mean_run_ends_where_the_straight_run_ends() {
        let mut json: serde_json::Value =
            serde_json::from_str(crate::case::builtin::get("footing").unwrap()).unwrap();
        json["analysis"]["volumetric"] = "cell_mean".into();
        resumes_where_the_straight_run_ends(Case::from_json(&json.to_string()).unwrap());
    }

    fn resumes_where_the_straight_run_ends(case: Case) {
        let mut straight = Simulation::new(&case).unwrap();
        let whole: RunReport = straight.run(&mut crate::NoObserver).unwrap();

        let mut first = Simulation::new(&case).unwrap();
        let mut stop = StopAfter {
            stop_after: 4,
            taken: None,
        };
        assert!(matches!(
            first.run(&mut stop),
            Err(SolveError::Cancelled { .. })
        ));
        let bytes = stop.taken.expect("a checkpoint after step 4");
        let checkpoint = Checkpoint::from_bytes(&bytes).unwrap();
        assert_eq!(checkpoint.steps_done(), 4);

        let mut resumed = Simulation::new(&case).unwrap();
        resumed.restore(&checkpoint).unwrap();
        // What the averaged stresses carry across the grid's reset (F-bar's
        // pressures, the cell mean's stresses) is state.
        let n = resumed.points.len();
        assert_eq!(
            checkpoint.fbar_pressure.len() + checkpoint.cell_mean_stress.len(),
            n
        );
        assert_eq!(resumed.points.fbar_pressure, checkpoint.fbar_pressure);
        assert_eq!(
            resumed.points.cell_mean_stress,
            first.points.cell_mean_stress
        );
        let rest = resumed.run(&mut crate::NoObserver).unwrap();
        assert_eq!(rest.steps.len(), whole.steps.len() - 4);
        for (a, b) in rest.steps.iter().zip(&whole.steps[4..]) {
            assert_eq!(a.step, b.step);
            assert_eq!(
                (a.newton.iterations, a.substeps, a.cutbacks),
                (b.newton.iterations, b.substeps, b.cutbacks),
                "step {}",
                a.step
            );
        }
        // Rayon's sums may group differently from run to run, so the two
        // agree to round-off rather than bit for bit.
        let scale = 1.0 + whole.steps.last().unwrap().probes[0].displacement[1].abs();
        let worst = resumed
            .points
            .position
            .iter()
            .zip(&straight.points.position)
            .flat_map(|(a, b)| [(a[0] - b[0]).abs(), (a[1] - b[1]).abs()])
            .fold(0.0, f64::max);
        assert!(worst <= 1e-12 * scale, "positions differ by {worst:e}");
        let stress_scale = 1e5;
        let worst = resumed
            .points
            .stress
            .iter()
            .zip(&straight.points.stress)
            .flat_map(|(a, b)| (0..3).map(move |k| (a.plane[k] - b.plane[k]).abs()))
            .fold(0.0, f64::max);
        assert!(
            worst <= 1e-9 * stress_scale,
            "stresses differ by {worst:e} Pa"
        );
        assert_eq!(
            resumed.points.yielding, straight.points.yielding,
            "the same points flow"
        );
    }

    /// A staged run (an elastic block confined with its top held, then
    /// pushed, then its top released and the pressure taken off) stopped
    /// inside its second stage and at the boundary of its third, resumed
    /// in a fresh simulation: each ends where the straight run ends, to the
    /// bit (a small run: rayon does not split its sums), in the same
    /// stage, with the released support's anchors gone.
    #[test]
    fn a_staged_run_resumes_in_its_stage() {
        let top = |d: f64| serde_json::json!({ "on": { "y": 1.0 }, "fix": "y", "method": "ibm", "displacement": [0.0, d] });
        let rollers = serde_json::json!([
            { "on": { "x": 0.0 }, "fix": "normal", "method": "ibm" },
            { "on": { "y": 0.0 }, "fix": "normal", "method": "ibm" }
        ]);
        let mut v = crate::fixtures::block([1.0, 1.0], [8, 8], 0.25, [0.1, 0.07]);
        v["analysis"] = serde_json::json!({});
        v["basis"] = "gimp".into();
        let with = |extra: serde_json::Value| {
            let mut all = rollers.as_array().unwrap().clone();
            all.push(extra);
            serde_json::Value::Array(all)
        };
        v["stages"] = serde_json::json!([
            { "name": "confine", "load_steps": 2, "supports": with(top(0.0)),
              "loads": { "boundary": [{ "on": { "x": 1.0 }, "pressure": 2.0e4 }] } },
            { "name": "push", "load_steps": 3, "supports": with(top(-0.02)) },
            { "name": "release", "load_steps": 2, "supports": rollers, "loads": {} }
        ]);
        let case = Case::from_json(&v.to_string()).unwrap();
        let mut straight = Simulation::new(&case).unwrap();
        let whole = straight.run(&mut crate::NoObserver).unwrap();
        assert_eq!(whole.steps.len(), 7);
        assert_eq!(whole.steps[6].stage.as_deref(), Some("release"));
        assert_eq!(whole.steps[6].reactions.len(), 2);
        // Released and unloaded, the block is back to no stress, to
        // Newton's tolerance (measured: 1.6e-6 of the pressure).
        for s in &straight.points.stress {
            assert!(s.plane.iter().all(|x| x.abs() < 1e-5 * 2.0e4), "{s:?}");
        }
        resumes_to_the_bit(&case, &whole, &straight, &[3, 5]);
    }

    /// Stopped after each of `stops` and resumed in a fresh simulation,
    /// the run of `case` ends where the straight run (`whole`, leaving
    /// `straight`) ends, to the bit (a small run: rayon does not split its
    /// sums).
    fn resumes_to_the_bit(case: &Case, whole: &RunReport, straight: &Simulation, stops: &[usize]) {
        for &stop_after in stops {
            let mut first = Simulation::new(case).unwrap();
            first.solver = straight.solver;
            let mut stop = StopAfter {
                stop_after,
                taken: None,
            };
            assert!(first.run(&mut stop).is_err());
            let checkpoint = Checkpoint::from_bytes(&stop.taken.unwrap()).unwrap();
            let mut resumed = Simulation::new(case).unwrap();
            resumed.solver = straight.solver;
            resumed.restore(&checkpoint).unwrap();
            let rest = resumed.run(&mut crate::NoObserver).unwrap();
            assert_eq!(
                rest.steps,
                whole.steps[stop_after..]
                    .iter()
                    .cloned()
                    .map(|mut s| {
                        s.timings = rest.steps[s.step - stop_after - 1].timings;
                        s
                    })
                    .collect::<Vec<_>>()
            );
            assert_eq!(
                resumed.points.position, straight.points.position,
                "after {stop_after}"
            );
            assert_eq!(
                resumed.points.stress_slopes, straight.points.stress_slopes,
                "after {stop_after}"
            );
            assert_eq!(resumed.reduction, straight.reduction, "after {stop_after}");
        }
    }

    /// The self-weight column with 128 cells over its height (4,096 DOFs),
    /// its symmetric tangents solved by CG with a kept factor and with
    /// multigrid (the defaults from 40k and 150k DOFs, forced here), under
    /// a ten-thousandth of its weight: most of its steps take over the last
    /// step's pattern, and each makes its
    /// own factor or hierarchy, so a resumed run, whose checkpoint holds
    /// neither, ends where the straight run ends, to the bit. (With them
    /// carried across steps, the resumed steps' residuals differ.)
    #[test]
    fn runs_solved_by_cg_resume_to_the_bit() {
        use crate::linsolve::{SolverSettings, SymmetricMethod};
        let mut v: serde_json::Value =
            serde_json::from_str(crate::case::builtin::get("column").unwrap()).unwrap();
        let h = 50.0 / 128.0;
        v["grid"]["cell_size"] = h.into();
        // A ten-thousandth of the weight: few points leave their cells.
        v["bodies"][0]["material"]["density"] = 0.008.into();
        v["grid"]["extent"]["max"] = serde_json::json!([16.0 * h, 50.0]);
        v["bodies"][0]["geometry"]["rectangle"]["max"] = serde_json::json!([16.0 * h, 50.0]);
        v["supports"][1]["on"]["x"] = (16.0 * h).into();
        v["probes"][0]["at"] = serde_json::json!([8.0 * h, 50.0]);
        let case = Case::from_json(&v.to_string()).unwrap();
        for method in [SymmetricMethod::KeptFactorCg, SymmetricMethod::Multigrid] {
            let mut straight = Simulation::new(&case).unwrap();
            straight.solver = SolverSettings {
                symmetric: Some(method),
                ..SolverSettings::default()
            };
            let whole = straight.run(&mut crate::NoObserver).unwrap();
            let counts = straight.solve_counts();
            assert!(
                counts.reused >= 10 && counts.cg_solves > 0,
                "{method:?} {counts:?}"
            );
            resumes_to_the_bit(&case, &whole, &straight, &[10, 30]);
        }
    }

    /// An arc-length run (a von Mises block squeezed by a pressure on its
    /// top, past its yield onto its plateau) resumes on the arc it was
    /// on: stopped after its first step (an equal increment, which sets
    /// the arc) and after a later one, it ends where the straight run
    /// ends, to the bit.
    #[test]
    fn an_arc_length_run_resumes_on_its_arc() {
        let mut v = crate::fixtures::block([1.0, 1.0], [8, 8], 0.25, [0.0, 0.0]);
        v["analysis"] = serde_json::json!({ "load_steps": 6, "control": "arc_length" });
        v["bodies"][0]["material"] = serde_json::json!({
            "model": "von_mises", "youngs_modulus": 1e6, "poisson_ratio": 0.3,
            "density": 0.0, "yield_stress": 1e3
        });
        v["loads"] = serde_json::json!({ "boundary": [{ "on": { "y": 1.0 }, "pressure": 3e3 }] });
        v["supports"] = serde_json::json!([{ "on": { "x": 0.0 }, "fix": "x" }, { "on": { "y": 0.0 }, "fix": "y" }]);
        let case = Case::from_json(&v.to_string()).unwrap();
        let mut straight = Simulation::new(&case).unwrap();
        let whole = straight.run(&mut crate::NoObserver).unwrap();
        // Past yield (a plane-strain block flows at 2 sigma_y / sqrt 3 =
        // 1155 Pa, 0.385 of the pressure asked) within its steps.
        let last = whole.steps.last().unwrap().load_factor;
        assert!(last > 0.3 && last < 0.5, "{last}");
        resumes_to_the_bit(&case, &whole, &straight, &[1, 4]);
    }

    /// A beam seeded one point a cell, bent by a tip load in four steps,
    /// resumes with its points' stress slopes (what the stabilisation of
    /// one-point cells holds of the bending): stopped after its second
    /// step, it ends where the straight run ends, to the bit.
    #[test]
    fn a_one_point_a_cell_beam_resumes_with_its_stress_slopes() {
        let mut v = crate::fixtures::block([4.0, 1.0], [8, 2], 0.5, [0.0, 0.0]);
        v["analysis"] = serde_json::json!({ "load_steps": 4 });
        v["basis"] = "gimp".into();
        v["loads"] =
            serde_json::json!({ "boundary": [{ "on": { "x": 4.0 }, "traction": [0.0, -2e3] }] });
        v["supports"] = serde_json::json!([{ "on": { "x": 0.0 }, "fix": "xy" }]);
        let case = Case::from_json(&v.to_string()).unwrap();
        let mut straight = Simulation::new(&case).unwrap();
        let whole = straight.run(&mut crate::NoObserver).unwrap();
        let bent = straight
            .points
            .stress_slopes
            .iter()
            .flatten()
            .filter(|s| s.abs() > 1.0);
        assert!(bent.count() > 8, "the slopes hold the bending");
        resumes_to_the_bit(&case, &whole, &straight, &[2]);
    }

    /// The paper's cantilever on GIMP with 5,120 points (about 3,000
    /// DOFs): its follower pressure's tangent is solved by GMRES,
    /// preconditioned by a kept factor of its symmetric part
    /// (`linsolve::UnsymmetricMethod`), which starts each load step
    /// afresh, so a resumed run, whose checkpoint holds no factor, ends
    /// where the straight run ends, to the bit. (With the factor kept
    /// across steps, the resumed steps' residuals differ.)
    #[test]
    fn a_run_solved_by_gmres_resumes_to_the_bit() {
        let mut v: serde_json::Value =
            serde_json::from_str(crate::case::builtin::get("cantilever").unwrap()).unwrap();
        v["basis"] = "gimp".into();
        v["grid"]["cell_size"] = 0.125.into();
        v["bodies"][0]["points"] = serde_json::json!({ "count": [160, 32] });
        // A hundredth of the load: few points leave their cells, so most
        // steps take over the last one's solver, and with it whatever
        // GMRES kept.
        v["loads"]["boundary"][0]["pressure"] = 15.0.into();
        let case = Case::from_json(&v.to_string()).unwrap();
        let mut straight = Simulation::new(&case).unwrap();
        let whole = straight.run(&mut crate::NoObserver).unwrap();
        assert!(straight.solve_counts().reused >= 3);
        for step in &whole.steps {
            assert_eq!(
                step.newton.factorisation,
                Some(crate::linsolve::Factorisation::Gmres),
                "step {}",
                step.step
            );
        }
        resumes_to_the_bit(&case, &whole, &straight, &[2]);
    }

    /// A strength-reduction run (the same block flowing at `2 sigma_y /
    /// sqrt 3 = 1154.7 Pa`, loaded to 1154.7 / 1.23 Pa, then reduced: its
    /// factor of safety is 1.23) resumes where its bisection stood:
    /// stopped after its first trial and after a step that followed a
    /// failed one, it ends where the straight run ends, to the bit.
    #[test]
    fn a_strength_reduction_resumes_where_its_bisection_stood() {
        let mut v = crate::fixtures::block([1.0, 1.0], [8, 8], 0.25, [0.0, 0.0]);
        let flow = 2.0 * 1e3 / 3f64.sqrt();
        v["analysis"] = serde_json::json!({});
        v["bodies"][0]["material"] = serde_json::json!({
            "model": "von_mises", "youngs_modulus": 1e6, "poisson_ratio": 0.3,
            "density": 0.0, "yield_stress": 1e3
        });
        v.as_object_mut().unwrap().remove("loads");
        v.as_object_mut().unwrap().remove("supports");
        v["stages"] = serde_json::json!([
            {
                "load_steps": 2,
                "loads": { "boundary": [{ "on": { "y": 1.0 }, "pressure": flow / 1.23 }] },
                "supports": [{ "on": { "x": 0.0 }, "fix": "x" }, { "on": { "y": 0.0 }, "fix": "y" }]
            },
            { "load_steps": 20, "strength_reduction": { "increment": 0.1, "tolerance": 0.01, "flow_limit": 10.0 } }
        ]);
        let case = Case::from_json(&v.to_string()).unwrap();
        let mut straight = Simulation::new(&case).unwrap();
        let whole = straight.run(&mut crate::NoObserver).unwrap();
        let last = whole
            .steps
            .last()
            .unwrap()
            .strength_reduction
            .clone()
            .unwrap();
        assert!(last.found, "{last:?}");
        assert!(
            last.factor <= 1.23 && last.failed.unwrap() > 1.23,
            "{last:?}"
        );
        // The flow limit measured every trial that held (the block's
        // points, all yielding at once, move too little on the grid for
        // it to cut one), and a resumed run carries what they travelled
        // (`resumes_to_the_bit` compares the reduction's state).
        let reduced = (whole.steps.iter()).filter_map(|s| s.strength_reduction.as_ref());
        let held: Vec<_> = reduced.filter(|r| !r.found).collect();
        assert!(
            held.len() >= 3 && held.iter().all(|r| r.flow.is_some()),
            "{held:?}"
        );
        let travelled = straight.reduction.as_ref().map(|r| r.travelled);
        assert!(travelled.is_some_and(|t| t > 0.0), "{travelled:?}");
        let after_failure = (whole.steps.iter())
            .position(|s| s.cutbacks > 0 && s.newton.iterations > 0)
            .expect("a trial that held after one that failed");
        resumes_to_the_bit(&case, &whole, &straight, &[3, after_failure + 1]);
    }

    #[test]
    fn a_checkpoint_round_trips_and_is_compact() {
        let case = footing();
        let sim = Simulation::new(&case).unwrap();
        let checkpoint = sim.checkpoint();
        let bytes = checkpoint.to_bytes();
        assert_eq!(Checkpoint::from_bytes(&bytes).unwrap(), checkpoint);
        let per_point = bytes.len() as f64 / sim.points.len() as f64;
        assert!(
            (129.0..150.0).contains(&per_point),
            "{per_point} bytes a point"
        );
    }

    #[test]
    fn a_checkpoint_of_another_case_or_garbage_is_refused() {
        let footing_state = Simulation::new(&footing()).unwrap().checkpoint();
        let column = Case::from_json(crate::case::builtin::get("column").unwrap()).unwrap();
        let mut other = Simulation::new(&column).unwrap();
        assert!(matches!(
            other.restore(&footing_state),
            Err(CheckpointError::OtherCase(_))
        ));
        assert!(matches!(
            Checkpoint::from_bytes(b"not a checkpoint"),
            Err(CheckpointError::Unreadable(_))
        ));
        let mut other_loops = footing_state.clone();
        other_loops.loops[0].points.reverse();
        assert_eq!(
            Simulation::new(&footing()).unwrap().restore(&other_loops),
            Err(CheckpointError::OtherCase("the boundary loops"))
        );
        let mut later_format = footing_state.clone();
        later_format.format = FORMAT + 1;
        assert!(matches!(
            Checkpoint::from_bytes(&later_format.to_bytes()),
            Err(CheckpointError::Unreadable(_))
        ));
    }
}
