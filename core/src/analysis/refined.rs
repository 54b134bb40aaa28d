//! One string rendered outside the tiers' configurations, for the offline comparisons of
//! `docs/modal-tanpura.md`, section 9: the reference tier's string on a refined grid (the
//! yardstick against which the bench, the examples and the tests measure the reference's own
//! discretisation error), and a modal tier's string at another sample rate or with residual
//! modes (section 8).
//!
//! The seed's FD scheme (seed 000, eq. 5–9) with `refinement` times the reference tier's
//! intervals and oversampling and the barrier's points as they are (finer than any of these
//! grids), configured, tuned by the voice's own [`tune_tension`] (passes of
//! `T ← T (f / f_lin)²` on the linearised fundamental), plucked and picked up as the reference
//! tier's voice does, through the tiers' Kaiser decimator. With `refinement = 1` it is the
//! reference tier's string itself.
//! Offline only: it allocates, and N = 800 at 16× does 16 times the reference tier's work per
//! second of sound (slower than real time).
//!
//! [`modal_pluck`] builds a modal tier's string as the voice builds it (`VoiceSettings::
//! modal_config_at`, f32 modes), tunes it by the same passes, plucks it and picks it up as the
//! voice does; with the voice's sample rate and no residual modes it is the voice's output.
//! [`modal_variant_pluck`] does the same for a string that departs from its tier's in its time
//! step or its bridge points ([`ModalVariant`]), to rule those out as causes of the tier's
//! distance from the reference.
//!
//! **The playing-range grid against the physics.** [`grid_render_refined`] renders a pluck of
//! the bench's grid on the reference's string refined [`YARDSTICK_REFINEMENT`] times (N = 800
//! at 16×, which N = 1600 at 32× moves by 1.8–4.2 dB and 2–9 % on the grid's measures at keys
//! 51–60, where the seed's grid lies 5–14 dB and 7–89 % from it), and [`grid_render_linearised`]
//! the same pluck on a tier's voice; both tuned by linearisation, so that the schemes are compared
//! at equal physical parameters (`docs/modal-tanpura.md` section 9, "Stop 35").

use crate::analysis::playing_range::{calibration_request, GridPoint, NOTE_SECONDS};
use crate::tanpura::excitation::Pluck;
use crate::tanpura::fd::decimator::render_decimated;
use crate::tanpura::fd::FdString;
use crate::tanpura::modal::ModalString;
use crate::tanpura::quality::Quality;
use crate::tanpura::tier_string::weighted_pickup_n;
use crate::tanpura::voice::tune_tension;
use crate::tanpura::{TanpuraVoice, VoiceSettings};

/// A render of [`refined_reference_pluck`]: the grid it ran on and its output at the output rate.
#[derive(Debug, Clone)]
pub struct RefinedRender {
    pub intervals: usize,
    pub oversample: usize,
    pub output: Vec<f64>,
}

/// `pluck` on the string of `settings` (its pitch, losses, bridge, thread and pickup; the tier
/// is always the reference's, refined `refinement` times), `seconds` long at `sample_rate_hz`.
/// `None` if the tier has no FD string or the tuning finds no fundamental.
pub fn refined_reference_pluck(
    settings: &VoiceSettings,
    refinement: usize,
    pluck: &Pluck,
    seconds: f64,
    sample_rate_hz: f64,
) -> Option<RefinedRender> {
    let tier = Quality::Reference.fd_tier()?;
    let refinement = refinement.max(1);
    reference_pluck_on_grid(
        settings,
        tier.intervals * refinement,
        tier.oversample * refinement,
        pluck,
        seconds,
        sample_rate_hz,
    )
}

/// [`refined_reference_pluck`] on any grid of the seed's scheme: `intervals` along the string
/// and `oversample` times `sample_rate_hz` (each at least 1; the barrier's points as the
/// reference's), to tell the grid's spatial error from its temporal one.
pub fn reference_pluck_on_grid(
    settings: &VoiceSettings,
    intervals: usize,
    oversample: usize,
    pluck: &Pluck,
    seconds: f64,
    sample_rate_hz: f64,
) -> Option<RefinedRender> {
    let (intervals, oversample) = (intervals.max(1), oversample.max(1));
    let mut config = settings.fd_config_at(Quality::Reference, sample_rate_hz)?;
    config.intervals = intervals;
    config.time_step_s = 1.0 / (sample_rate_hz * oversample as f64);
    let mut string = FdString::new(config);
    tune_tension(
        &mut string,
        settings.fundamental_hz,
        FdString::linearised_fundamental_hz,
        |string| string.config().string.tension_n,
        |string, tension| {
            config.string.tension_n = tension;
            string.set_config(config);
        },
    )?;
    string.pluck(pluck);
    let samples = (seconds * sample_rate_hz) as usize;
    let output = render_decimated(oversample, samples, || {
        string.step();
        weighted_pickup_n(
            settings.nut_pickup_weight,
            string.nut_force_n() - string.rest_nut_force_n(),
            string.bridge_force_n() - string.rest_bridge_force_n(),
        )
    })
    .into_iter()
    // The voice's output is f32.
    .map(|sample| f64::from(sample as f32))
    .collect();
    Some(RefinedRender {
        intervals,
        oversample,
        output,
    })
}

/// `pluck` on the modal string of `settings` (whose tier must be modal) at `sample_rate_hz`
/// with `residual_modes` residual modes, `seconds` long at that rate. `None` if the tier is not
/// modal or the tuning finds no fundamental.
pub fn modal_pluck(
    settings: &VoiceSettings,
    sample_rate_hz: f64,
    residual_modes: usize,
    pluck: &Pluck,
    seconds: f64,
) -> Option<Vec<f64>> {
    let variant = ModalVariant {
        residual_modes,
        ..ModalVariant::default()
    };
    modal_variant_pluck(settings, &variant, pluck, seconds, sample_rate_hz)
}

/// How [`modal_variant_pluck`]'s string departs from its tier's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModalVariant {
    /// Residual modes (`docs/modal-tanpura.md` §8); the tiers have none.
    pub residual_modes: usize,
    /// Steps per output sample, through the oversampled tiers' decimator (the studio tier takes
    /// two).
    pub oversample: usize,
    /// The bridge's points every this many metres instead of the tier's spacing.
    pub bridge_point_spacing_m: Option<f64>,
    /// The thread's points every this many metres instead of the tier's spacing.
    pub thread_point_spacing_m: Option<f64>,
    /// Every mode of the reference tier's FD grid instead of the continuous string's
    /// ([`reference_grid_modes`], `docs/modal-tanpura.md` §10).
    pub grid_modes: bool,
}

pub use crate::tanpura::quality::reference_grid_modes;

impl Default for ModalVariant {
    fn default() -> Self {
        Self {
            residual_modes: 0,
            oversample: 1,
            bridge_point_spacing_m: None,
            thread_point_spacing_m: None,
            grid_modes: false,
        }
    }
}

/// [`modal_pluck`] with the string of `variant`: residual modes, a shorter time step (the string
/// run at `oversample` times `sample_rate_hz`, keeping the tier's highest mode, then decimated) or
/// other bridge points. With the default variant it is [`modal_pluck`] without residual modes.
pub fn modal_variant_pluck(
    settings: &VoiceSettings,
    variant: &ModalVariant,
    pluck: &Pluck,
    seconds: f64,
    sample_rate_hz: f64,
) -> Option<Vec<f64>> {
    let oversample = variant.oversample.max(1);
    let mut config =
        settings.modal_config_at(settings.quality, sample_rate_hz * oversample as f64)?;
    config.residual_modes = variant.residual_modes;
    if variant.grid_modes {
        config.grid_modes = Some(reference_grid_modes(sample_rate_hz));
    }
    if let Some(spacing_m) = variant.bridge_point_spacing_m {
        config.bridge_point_spacing_m = spacing_m;
    }
    if let Some(spacing_m) = variant.thread_point_spacing_m {
        config.thread_point_spacing_m = spacing_m;
    }
    let mut string = ModalString::<f32>::new(config);
    tune_tension(
        &mut string,
        settings.fundamental_hz,
        ModalString::linearised_fundamental_hz,
        |string| string.config().string.tension_n,
        |string, tension| {
            config.string.tension_n = tension;
            string.set_config(config);
        },
    )?;
    string.pluck(pluck);
    let samples = (seconds * sample_rate_hz) as usize;
    let mut next = || {
        string.step();
        weighted_pickup_n(
            settings.nut_pickup_weight,
            string.nut_force_change_n(),
            string.bridge_force_change_n(),
        )
    };
    let output = if oversample == 1 {
        (0..samples).map(|_| next()).collect()
    } else {
        render_decimated(oversample, samples, next)
    };
    // The voice's output is f32.
    Some(output.into_iter().map(|x| f64::from(x as f32)).collect())
}

/// The refinement of the bench's physical yardstick: N = 800 at 16×.
pub const YARDSTICK_REFINEMENT: usize = 4;

/// The yardstick's grid: its intervals and its oversampling of the output rate.
pub fn yardstick_grid() -> (usize, usize) {
    let tier = Quality::Reference
        .fd_tier()
        .expect("the reference tier is an FD tier");
    (
        tier.intervals * YARDSTICK_REFINEMENT,
        tier.oversample * YARDSTICK_REFINEMENT,
    )
}

/// The string settings of `point` on `quality` as the engine plans them (its note's pitch, the
/// instrument's bridge, thread and losses) and its pluck at the point's velocity.
pub fn grid_pluck(quality: Quality, point: &GridPoint) -> (VoiceSettings, Pluck) {
    let request = calibration_request(quality, point.key, point.pluck_position_m);
    let pluck = Pluck {
        amplitude_m: request.pluck.amplitude_m * f64::from(point.velocity) / 127.0,
        ..request.pluck
    };
    (request.settings, pluck)
}

/// [`NOTE_SECONDS`] of `point` on a fresh voice of `quality` tuned by linearisation (the voice's
/// output, without the engine's output gain); a modal tier with `residual_modes` residual modes
/// through [`modal_pluck`] (with none it is the voice's output bit for bit).
pub fn grid_render_linearised(
    quality: Quality,
    point: &GridPoint,
    sample_rate_hz: f64,
    residual_modes: usize,
) -> Vec<f64> {
    let (settings, pluck) = grid_pluck(quality, point);
    if residual_modes > 0 {
        if let Some(output) = modal_pluck(
            &settings,
            sample_rate_hz,
            residual_modes,
            &pluck,
            NOTE_SECONDS,
        ) {
            return output;
        }
    }
    let mut voice = TanpuraVoice::new(&settings, sample_rate_hz);
    voice.pluck(&pluck);
    (0..(NOTE_SECONDS * sample_rate_hz).round() as usize)
        .map(|_| f64::from(voice.next_sample()))
        .collect()
}

/// [`NOTE_SECONDS`] of `point` on the reference's string refined [`YARDSTICK_REFINEMENT`] times,
/// tuned by linearisation (empty if the tuning finds no fundamental). Sixteen times the
/// reference tier's work: offline.
pub fn grid_render_refined(point: &GridPoint, sample_rate_hz: f64) -> Vec<f64> {
    let (settings, pluck) = grid_pluck(Quality::Reference, point);
    refined_reference_pluck(
        &settings,
        YARDSTICK_REFINEMENT,
        &pluck,
        NOTE_SECONDS,
        sample_rate_hz,
    )
    .map_or_else(Vec::new, |render| render.output)
}
