//! The modal string with the reference's FD grid as its modes (`ModalStringConfig::grid_modes`,
//! `docs/modal-tanpura.md` §10): every mode of the grid is kept, those above Nyquist included, so
//! the discrete energy balance of eq. M3 must still hold in contact, and the static problems see
//! the grid's whole compliance, so the string must rest where the FD string rests. (That its free
//! partials are the FD scheme's own is checked beside the FD's in `tanpura_invariants.rs`.)

use javari_core::analysis::refined::reference_grid_modes;
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::fd::barrier_grid::lagrange_stencil;
use javari_core::tanpura::fd::{FdString, FdStringConfig};
use javari_core::tanpura::modal::{ModalString, ModalStringConfig};

const SAMPLE_RATE: f64 = 44_100.0;

/// The modal string of `config` on the reference's grid.
fn on_the_grid(mut config: ModalStringConfig) -> ModalStringConfig {
    config.grid_modes = Some(reference_grid_modes(SAMPLE_RATE));
    config
}

#[test]
fn grid_modes_keep_the_energy_balance_in_contact() {
    let mut lossless = on_the_grid(ModalStringConfig::REFERENCE.lossless());
    lossless.track_energy = true;
    let mut string = ModalString::<f64>::new(lossless);
    assert_eq!(
        string.modes().count(),
        199,
        "every mode of the 200-interval grid"
    );
    string.pluck(&Pluck::default());
    let initial = string.energy_j();
    let mut worst_drift = 0.0f64;
    for _ in 0..(0.5 * SAMPLE_RATE) as usize {
        string.step();
        worst_drift = worst_drift.max((string.energy_j() - initial).abs() / initial);
    }
    let stats = *string.newton_stats();
    assert!(
        stats.steps_without_contact < stats.steps / 10,
        "the balance is tested in contact: {stats:?}"
    );
    assert!(
        worst_drift <= 1e-10,
        "relative energy drift {worst_drift:e}"
    );

    let mut lossy = on_the_grid(ModalStringConfig::REFERENCE);
    lossy.track_energy = true;
    let mut string = ModalString::<f64>::new(lossy);
    string.pluck(&Pluck::default());
    let initial = string.energy_j();
    let mut previous = initial;
    let (mut worst_rise, mut worst_balance) = (0.0f64, 0.0f64);
    for _ in 0..(0.5 * SAMPLE_RATE) as usize {
        string.step();
        let energy = string.energy_j();
        worst_rise = worst_rise.max((energy - previous) / initial);
        worst_balance =
            worst_balance.max((energy + string.cumulative_losses_j() - initial).abs() / initial);
        previous = energy;
    }
    assert!(string.cumulative_losses_j() > 0.0);
    assert!(worst_rise <= 1e-14, "H rose by {worst_rise:e} of H(0)");
    assert!(worst_balance <= 1e-10, "balance error {worst_balance:e}");
    assert_eq!(string.newton_stats().cap_hits, 0);
}

/// The FD string's rest displacement at `x_m`, by the scheme's own cubic interpolation.
fn fd_rest_at_m(string: &FdString, x_m: f64) -> f64 {
    let config = string.config();
    let spacing = config.string.length_m / config.intervals as f64;
    let (first, weights) = lagrange_stencil(x_m / spacing, config.intervals);
    let rest = string.rest_displacement_m();
    (0..4).map(|j| weights[j] * rest[first + j]).sum()
}

/// At the tensions of the keys where the reference's string starts to rest on the bridge's crest
/// (section 9) and of key 60, the string with grid modes and contact points as fine as the
/// reference's barrier grids rests where the reference's FD string rests: its rest shape at every
/// contact point (measured: within 0.04–0.14 µm) and its linearised fundamental (0.13–0.16
/// cents). The continuous modes on the same points, as the tiers run, lie micrometres away (the
/// truncated modes' ripple at the thread, section 8), which this test would catch.
#[test]
fn grid_modes_rest_where_the_reference_grid_rests() {
    let seed = FdStringConfig::REFERENCE;
    let seed_hz = FdString::new(seed).linearised_fundamental_hz();
    for key in [49u8, 51, 54, 60] {
        let key_hz = 440.0 * ((f64::from(key) - 69.0) / 12.0).exp2();
        let tension_n = seed.string.tension_n * (key_hz / seed_hz).powi(2);
        let mut fd_config = seed;
        fd_config.string.tension_n = tension_n;
        let mut fd = FdString::new(fd_config);
        let fd_hz = fd.linearised_fundamental_hz();
        let mut config = ModalStringConfig::REFERENCE;
        config.string.tension_n = tension_n;
        config.bridge_point_spacing_m = 0.18e-3;
        config.thread_point_spacing_m = 0.15e-3;
        let measure = |config: ModalStringConfig| {
            let mut modal = ModalString::<f64>::new(config);
            let worst_um = modal
                .point_positions_m()
                .iter()
                .map(|&x| (modal.rest_displacement_at_m(x) - fd_rest_at_m(&fd, x)).abs() * 1e6)
                .fold(0.0, f64::max);
            let cents = 1200.0 * (modal.linearised_fundamental_hz() / fd_hz).log2();
            (worst_um, cents)
        };
        let (grid_um, grid_cents) = measure(on_the_grid(config));
        let (continuous_um, _) = measure(config);
        assert!(
            grid_um < 0.2,
            "key {key}: grid modes {grid_um} µm from the FD"
        );
        assert!(
            grid_cents.abs() < 0.25,
            "key {key}: grid modes' linearised fundamental {grid_cents} cents"
        );
        assert!(
            continuous_um > 1.0,
            "key {key}: the continuous modes lie only {continuous_um} µm from the FD"
        );
    }
}
