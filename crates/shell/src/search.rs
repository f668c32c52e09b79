//! The paper's simulation loop (Gingold et al. 2004): each step of length `dt` is covered by
//! sub-steps of `dt 2^-k`; a trial sub-step is discarded whole (positions, velocities, forces,
//! plastic state) and retried at `k + 1` when the largest force grew by more than a factor or
//! a triangle would break in it (past its threshold by more than `overshoot`), or when it ran
//! away (a non-finite energy) or its implicit solve needed more than `trial_iterations`. At
//! `k = levels` a sub-step is always taken. After a sub-step is taken the plastic state is
//! updated (inside its force pass), over-strained triangles break, and `k` falls by one; `k`
//! carries over from step to step, so steps stay fine while forces keep jumping.

use perifrac_checkpoint::{CheckpointError, Reader, Writer};

use crate::dynamics::{ShellDynamics, Snapshot};
use crate::error::{bad_setting, ShellError};
use crate::fracture::FractureEvent;

/// The search's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShellSearch {
    /// Finest level `k_max` (at most 20; the paper uses 10).
    pub levels: u32,
    /// A trial is discarded when the largest force after it passes this factor times the
    /// largest before it (> 1; the paper's 1.1).
    pub force_growth: f64,
    /// ... or when a triangle in it passes its fracture threshold by more than this share
    /// (>= 0; 0, the paper's: every fracture is found at the finest level).
    pub overshoot: f64,
    /// Implicit steps: a trial whose solve needs more L-BFGS iterations than this is undone
    /// and halved (>= 1; the sub-step at the finest level is solved to the settings' own
    /// cap).
    pub trial_iterations: usize,
    /// Forces under this share of the largest seen so far cannot reject a trial for growing
    /// (in [0, 1)); growth is also judged from no less than the model's force scale
    /// ([`crate::ShellModel::force_scale`]).
    pub force_floor: f64,
}

impl Default for ShellSearch {
    fn default() -> Self {
        ShellSearch {
            levels: 10,
            force_growth: 1.1,
            overshoot: 0.0,
            trial_iterations: 30,
            force_floor: 1e-3,
        }
    }
}

impl ShellSearch {
    /// Refuses settings out of range.
    pub fn check(&self) -> Result<(), ShellError> {
        if self.levels > 20 {
            return bad_setting("shell search levels", "at most 20", self.levels as f64);
        }
        if self.force_growth.is_nan() || self.force_growth <= 1.0 {
            return bad_setting("shell search force growth", "above 1", self.force_growth);
        }
        if self.overshoot.is_nan() || self.overshoot < 0.0 {
            return bad_setting("shell search overshoot", ">= 0", self.overshoot);
        }
        if self.trial_iterations == 0 {
            return bad_setting("shell search trial iterations", "at least 1", 0.0);
        }
        if !(0.0..1.0).contains(&self.force_floor) {
            return bad_setting("shell search force floor", "in [0, 1)", self.force_floor);
        }
        Ok(())
    }
}

/// What the search did over one or more steps.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SearchStats {
    /// Sub-steps taken.
    pub substeps: u64,
    /// Trial sub-steps discarded.
    pub rejected: u64,
    /// Of those, for a force that grew too fast.
    pub rejected_force: u64,
    /// Of those, for a triangle that would break.
    pub rejected_fracture: u64,
    /// Of those, for an implicit solve that reached its iteration cap.
    pub rejected_solve: u64,
    /// Triangles broken.
    pub events: Vec<FractureEvent>,
}

/// A shell (stepped explicitly or by Newmark) under the search: the shell, the settings, the current level and the
/// largest force seen.
#[derive(Debug, Clone)]
pub struct SearchedShell {
    shell: ShellDynamics,
    config: ShellSearch,
    k: u32,
    peak: f64,
    stats: SearchStats,
    snapshot: Snapshot,
}

impl SearchedShell {
    /// Wraps `shell`; checks the settings.
    pub fn new(shell: ShellDynamics, config: ShellSearch) -> Result<SearchedShell, ShellError> {
        config.check()?;
        let peak = shell.largest_force();
        Ok(SearchedShell {
            shell,
            config,
            k: 0,
            peak,
            stats: SearchStats::default(),
            snapshot: Snapshot::default(),
        })
    }

    /// The shell.
    pub fn shell(&self) -> &ShellDynamics {
        &self.shell
    }

    /// The shell, to change (velocities, pins).
    pub fn shell_mut(&mut self) -> &mut ShellDynamics {
        &mut self.shell
    }

    /// What the search did so far.
    pub fn stats(&self) -> &SearchStats {
        &self.stats
    }

    /// The level of the next trial sub-step.
    pub fn level(&self) -> u32 {
        self.k
    }

    /// Writes the shell, the search's level, its largest force seen and its counts for a
    /// checkpoint (between steps).
    pub fn write_checkpoint(&self, w: &mut Writer) {
        w.tag("shell search");
        self.shell.write_checkpoint(w);
        w.u64(u64::from(self.k));
        w.f64(self.peak);
        let st = &self.stats;
        for n in [
            st.substeps,
            st.rejected,
            st.rejected_force,
            st.rejected_fracture,
            st.rejected_solve,
        ] {
            w.u64(n);
        }
        let faces: Vec<u64> = st.events.iter().map(|e| e.face as u64).collect();
        let ratios: Vec<f64> = st.events.iter().map(|e| e.ratio).collect();
        let budged: Vec<u8> = st.events.iter().map(|e| u8::from(e.budged)).collect();
        w.array(&faces);
        w.array(&ratios);
        w.array(&budged);
    }

    /// Reads what [`SearchedShell::write_checkpoint`] wrote into a search built by the same
    /// scene.
    pub fn read_checkpoint(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        r.tag("shell search")?;
        self.shell.read_checkpoint(r)?;
        let k = r.u64("search level")?;
        if k > u64::from(self.config.levels) {
            return Err(CheckpointError::Invalid {
                what: "shell search".into(),
                message: format!("level {k} past the finest, {}", self.config.levels),
            });
        }
        self.k = k as u32;
        self.peak = r.f64("largest force")?;
        let mut st = SearchStats::default();
        for (c, what) in [
            (&mut st.substeps, "sub-steps"),
            (&mut st.rejected, "trials undone"),
            (&mut st.rejected_force, "trials undone for force"),
            (&mut st.rejected_fracture, "trials undone for fracture"),
            (&mut st.rejected_solve, "trials undone for a solve"),
        ] {
            *c = r.u64(what)?;
        }
        let (mut faces, mut ratios, mut budged) = (Vec::<u64>::new(), Vec::new(), Vec::<u8>::new());
        r.array_vec("broken triangles", &mut faces)?;
        r.array_vec("their strain ratios", &mut ratios)?;
        r.array_vec("their budges", &mut budged)?;
        if ratios.len() != faces.len() || budged.len() != faces.len() {
            return Err(CheckpointError::Invalid {
                what: "shell search".into(),
                message: format!("{} events, {} ratios", faces.len(), ratios.len()),
            });
        }
        st.events = faces
            .iter()
            .zip(&ratios)
            .zip(&budged)
            .map(|((&face, &ratio), &b)| FractureEvent {
                face: face as usize,
                ratio,
                budged: b != 0,
            })
            .collect();
        self.stats = st;
        Ok(())
    }

    /// Covers one step of `dt` (s) by sub-steps.
    pub fn advance(&mut self, dt: f64) -> Result<(), ShellError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(ShellError::BadSetting {
                what: "shell time step (s)",
                expected: "finite and > 0",
                value: dt,
            });
        }
        let levels = self.config.levels;
        let full = 1u64 << levels;
        let mut done = 0u64;
        let breaks = self.shell.model().fracture_params().is_some();
        let scale = self.shell.model().force_scale();
        let mut before = self.shell.largest_force();
        while done < full {
            let units = (full >> self.k).min(full - done);
            let trial = self.k < levels;
            if trial {
                self.shell.save(&mut self.snapshot);
            }
            self.shell
                .set_solve_cap(trial.then_some(self.config.trial_iterations));
            let stepped = self.shell.step(dt * units as f64 / full as f64);
            // A trial that ran away is discarded like one whose force grew; at the finest
            // level the error stands.
            let ran_away = matches!(stepped, Err(ShellError::RanAway { .. }));
            if !(trial && ran_away) {
                stepped?;
            }
            let after = self.shell.largest_force();
            // Growth is judged from at least the force scale: round-off in free fall is not
            // a force, and the first contact is judged against the scale, not against nothing.
            // An implicit trial whose solve hit the trials' cap is no state to judge: shorter.
            let unsolved = trial && self.shell.last_solve_capped();
            let grew = ran_away
                || unsolved
                || (after > self.config.force_growth * before.max(scale)
                    && after > self.config.force_floor * self.peak);
            let cracks = trial
                && !grew
                && breaks
                && self.shell.worst_fracture_ratio()? > 1.0 + self.config.overshoot;
            if trial && (grew || cracks) {
                self.shell.restore(&self.snapshot);
                self.k += 1;
                self.stats.rejected += 1;
                if unsolved {
                    self.stats.rejected_solve += 1;
                } else if grew {
                    self.stats.rejected_force += 1;
                } else {
                    self.stats.rejected_fracture += 1;
                }
                continue;
            }
            if breaks {
                let r = self.shell.fracture()?;
                self.stats.events.extend(r.events);
            }
            let after = self.shell.largest_force();
            self.peak = self.peak.max(after);
            before = after;
            done += units;
            self.stats.substeps += 1;
            self.k = self.k.saturating_sub(1);
        }
        self.shell.set_solve_cap(None);
        Ok(())
    }
}
