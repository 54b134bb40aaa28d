//! The discretisations of the seed's string that the convergence examples (`grid_convergence`,
//! `crest_threshold`) compare: the FD scheme at a chosen grid and oversampling, the modal scheme
//! (f64) at a chosen point spacing with or without the truncated modes' compliance. Included by
//! `#[path]`; not an example of its own.

use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::fd::decimator::render_decimated;
use javari_core::tanpura::fd::{FdString, FdStringConfig};
use javari_core::tanpura::modal::{ModalString, ModalStringConfig};

pub const OUTPUT_RATE_HZ: f64 = 44_100.0;

/// A discretisation of the seed's string.
#[derive(Clone, Copy)]
pub enum Scheme {
    /// FD with `intervals` at `oversampling` × 44.1 kHz (the seed's barrier points).
    Fd(usize, usize),
    /// Modal (f64) at 44.1 kHz with bridge points `spacing` apart (the thread's half of it),
    /// `residual` residual modes and the static compliance frozen in (`flexibility`).
    Modal(f64, usize, bool),
}

impl Scheme {
    pub fn name(self) -> String {
        match self {
            Scheme::Fd(200, 4) => "FD N = 200, 4x (the reference)".to_owned(),
            Scheme::Fd(intervals, oversampling) => format!("FD N = {intervals}, {oversampling}x"),
            Scheme::Modal(spacing, residual, flexibility) => format!(
                "modal, {:.2} mm, {}",
                spacing * 1e3,
                match (residual, flexibility) {
                    (0, false) => "kept modes only".to_owned(),
                    (_, true) => "static compliance".to_owned(),
                    (residual, false) => format!("{residual} residual modes"),
                }
            ),
        }
    }

    /// The FD configuration at `tension_n` (the seed's with `None`).
    pub fn fd_config(
        intervals: usize,
        oversampling: usize,
        tension_n: Option<f64>,
    ) -> FdStringConfig {
        let mut config = FdStringConfig {
            intervals,
            time_step_s: 1.0 / (OUTPUT_RATE_HZ * oversampling as f64),
            ..FdStringConfig::REFERENCE
        };
        if let Some(tension_n) = tension_n {
            config.string.tension_n = tension_n;
        }
        config
    }

    /// The modal configuration at `tension_n` (the seed's with `None`).
    pub fn modal_config(
        spacing: f64,
        residual: usize,
        flexibility: bool,
        tension_n: Option<f64>,
    ) -> ModalStringConfig {
        let mut config = ModalStringConfig {
            bridge_point_spacing_m: spacing,
            thread_point_spacing_m: 0.5 * spacing,
            residual_modes: residual,
            static_flexibility: flexibility,
            ..ModalStringConfig::REFERENCE
        };
        if let Some(tension_n) = tension_n {
            config.string.tension_n = tension_n;
        }
        config
    }

    /// The nut force (the seed's signal) at 44.1 kHz for `seconds`, the string at `tension_n`
    /// (the seed's with `None`) plucked as the bench plucks at `velocity` (0–1), `position_m`
    /// from the bead (the bench's default pluck: `Pluck::default().position_m`); FD through the
    /// tiers' Kaiser decimator.
    pub fn pluck_nut_force(
        self,
        tension_n: Option<f64>,
        velocity: f64,
        position_m: f64,
        seconds: f64,
    ) -> Vec<f64> {
        let pluck = Pluck {
            amplitude_m: Pluck::default().amplitude_m * velocity,
            position_m,
            ..Pluck::default()
        };
        let samples = (seconds * OUTPUT_RATE_HZ).round() as usize;
        match self {
            Scheme::Fd(intervals, oversampling) => {
                let mut string = FdString::new(Self::fd_config(intervals, oversampling, tension_n));
                string.pluck(&pluck);
                render_decimated(oversampling, samples, || {
                    string.step();
                    string.nut_force_n()
                })
            }
            Scheme::Modal(spacing, residual, flexibility) => {
                let mut string: ModalString<f64> = ModalString::new(Self::modal_config(
                    spacing,
                    residual,
                    flexibility,
                    tension_n,
                ));
                string.pluck(&pluck);
                (0..samples)
                    .map(|_| {
                        string.step();
                        string.nut_force_n()
                    })
                    .collect()
            }
        }
    }
}

/// `work` on every job, on all of the machine's cores (rayon), the jobs started in the order
/// given (`par_bridge` hands them out as the iterator yields them: put the longest first, so
/// that the cores finish together); the results in the jobs' order.
pub fn on_all_cores<J: Sync, R: Send>(jobs: &[J], work: impl Fn(&J) -> R + Sync) -> Vec<R> {
    use rayon::prelude::*;
    let mut results: Vec<(usize, R)> = jobs
        .iter()
        .enumerate()
        .par_bridge()
        .map(|(index, job)| (index, work(job)))
        .collect();
    results.sort_by_key(|&(index, _)| index);
    results.into_iter().map(|(_, result)| result).collect()
}
