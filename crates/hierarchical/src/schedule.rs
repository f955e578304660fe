//! The three ways to interleave link refinement with solution (as Willmott 2000, §2.4.3, classifies them), driven one pass per step:
//!
//! - two-stage: link all input faces, refine until no link changes (the oracle sees emission only), then
//!   gather/push-pull until converged;
//! - interleaved: link, then alternate one refinement pass (each link refined at most once) and one solution
//!   pass, until a refinement pass changes nothing and the solution has converged;
//! - scheduled: stage i refines at ε_i until no link changes, then solves to convergence; ε_{i+1} = ε_i / α
//!   down to ε, then stages at ε until one changes nothing. With lazy linking each stage first links the
//!   faces that received light in the previous one (Holzschuch, Sillion & Drettakis 1994), so with α = 1 the
//!   stages are successive bounces.
//!
//! A step is one unit of work: a linking step, a refinement pass or a solution pass. Transitions that need no
//! work happen inside the step that follows them.

use radlab_method::{SolveError, Step};
use radlab_visibility::Accel;

use crate::hierarchy::{Engine, Phase};
use crate::node::NodeKind;
use crate::params::Schedule;
use crate::transport::Transport;

impl<N: NodeKind, T: Transport<N>> Engine<N, T> {
    /// The threshold of the current stage.
    pub fn current_epsilon(&self) -> f64 {
        match self.params.schedule {
            Schedule::Scheduled => self.params.stage_epsilon(self.schedule.stage),
            _ => self.params.epsilon,
        }
    }

    fn lazy(&self) -> bool {
        self.params.lazy_linking && self.params.schedule != Schedule::TwoStage
    }

    /// [`Engine::step`], adding the rays `accel` cast during it to `rays` (also when the step fails), so every
    /// solver on the engine counts its rays the same way.
    pub fn step_counting_rays(
        &mut self,
        accel: &Accel,
        rays: &mut u64,
    ) -> Result<Step, SolveError> {
        let before = accel.rays_cast();
        let s = self.step();
        *rays += accel.rays_cast().saturating_sub(before);
        s
    }

    /// One unit of work of the schedule.
    pub fn step(&mut self) -> Result<Step, SolveError> {
        if self.schedule.phase == Phase::Done {
            return Ok(Step::Converged);
        }
        if self.steps >= self.params.max_steps {
            self.schedule.phase = Phase::Done;
            return Ok(Step::Capped);
        }
        self.steps += 1;
        if self.shooting.is_some() {
            self.shoot_sweep()?;
            if self.solve.converged {
                self.schedule.phase = Phase::Done;
                return Ok(Step::Converged);
            }
            return Ok(Step::Continue);
        }
        let lazy = self.lazy();
        loop {
            match (self.params.schedule, self.schedule.phase) {
                (_, Phase::Done) => return Ok(Step::Converged),
                (Schedule::TwoStage, Phase::Link) => {
                    let all = self.pending_sources(false);
                    self.link_roots(&all)?;
                    self.schedule.phase = Phase::Refine;
                    return Ok(Step::Continue);
                }
                (Schedule::TwoStage, Phase::Refine) => {
                    if self.refine_pass(self.params.epsilon)? == 0 {
                        self.schedule.phase = Phase::Solve;
                        continue;
                    }
                    return Ok(Step::Continue);
                }
                (Schedule::TwoStage, Phase::Solve) => {
                    self.solve_pass()?;
                    if self.solve.converged {
                        self.schedule.phase = Phase::Done;
                        return Ok(Step::Converged);
                    }
                    return Ok(Step::Continue);
                }
                (Schedule::Interleaved, Phase::Link) => {
                    let new = self.pending_sources(lazy);
                    self.link_roots(&new)?;
                    self.schedule.refine_changed = true;
                    self.schedule.phase = Phase::Solve;
                    return Ok(Step::Continue);
                }
                (Schedule::Interleaved, Phase::Refine) => {
                    let new = self.pending_sources(lazy);
                    let made = if new.is_empty() {
                        0
                    } else {
                        self.link_roots(&new)?
                    };
                    let refined = self.refine_pass(self.params.epsilon)?;
                    self.schedule.refine_changed = !new.is_empty() || made + refined > 0;
                    self.schedule.phase = Phase::Solve;
                    return Ok(Step::Continue);
                }
                (Schedule::Interleaved, Phase::Solve) => {
                    self.solve_pass()?;
                    if self.solve.converged && !self.schedule.refine_changed {
                        self.schedule.phase = Phase::Done;
                        return Ok(Step::Converged);
                    }
                    self.schedule.phase = Phase::Refine;
                    return Ok(Step::Continue);
                }
                (Schedule::Scheduled, Phase::Link) => {
                    let new = self.pending_sources(lazy);
                    self.schedule.phase = Phase::Refine;
                    if new.is_empty() {
                        continue;
                    }
                    self.link_roots(&new)?;
                    self.schedule.stage_changed = true;
                    return Ok(Step::Continue);
                }
                (Schedule::Scheduled, Phase::Refine) => {
                    if self.refine_pass(self.current_epsilon())? > 0 {
                        self.schedule.stage_changed = true;
                        return Ok(Step::Continue);
                    }
                    self.schedule.phase = Phase::Solve;
                    continue;
                }
                (Schedule::Scheduled, Phase::Solve) => {
                    if !self.solve.converged {
                        self.solve_pass()?;
                        if !self.solve.converged {
                            return Ok(Step::Continue);
                        }
                    }
                    let last = self.schedule.stage + 1 >= self.params.stages;
                    if last && !self.schedule.stage_changed {
                        self.schedule.phase = Phase::Done;
                        return Ok(Step::Converged);
                    }
                    self.schedule.stage += 1;
                    self.schedule.stage_changed = false;
                    self.schedule.phase = Phase::Link;
                    // The pass just done was this step's work.
                    return Ok(Step::Continue);
                }
            }
        }
    }
}
