//! The modal string with the reference's FD grid as its modes (`ModalStringConfig::grid_modes`,
//! `docs/modal-tanpura.md` §10): every mode of the grid is kept, so the static problems see the
//! grid's whole compliance and the string must rest where the FD string rests; and its contact
//! condensed on the grid's nodes (§11) must play what the point-level solve plays. (Its energy
//! balance is checked with the other modal strings' in `tanpura_modal.rs`, its free partials
//! beside the FD's in `tanpura_invariants.rs`.)

use javari_core::analysis::refined::reference_grid_modes;
use javari_core::engine::pitch::note_to_hz;
use javari_core::tanpura::fd::barrier_grid::lagrange_stencil;
use javari_core::tanpura::fd::{FdString, FdStringConfig};
use javari_core::tanpura::modal::{ModalString, ModalStringConfig};

const SAMPLE_RATE: f64 = 44_100.0;

/// The modal string of `config` on the reference's grid.
fn on_the_grid(mut config: ModalStringConfig) -> ModalStringConfig {
    config.grid_modes = Some(reference_grid_modes(SAMPLE_RATE));
    config
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
        let tension_n = seed.string.tension_n * (note_to_hz(key) / seed_hz).powi(2);
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

/// The contact condensed on the grid's nodes (section 11) solves the same scheme as the
/// point-level solve (section 4): on points as fine as the reference's barrier grids, at the
/// tensions of a crest key and of key 60, the two play the same string, their pickup forces
/// within 1e-9 of the force's range over 0.3 s. Newton takes fewer updates on the nodes: both
/// solves finish a step with one crossing point exactly, the point-level one only while at most
/// 8 points are in contact, the nodal one always (measured since stop 43: 2.76 against 3.21 per
/// step at key 51, 2.19 against 2.72 and 1.07 against 1.10 at key 60; before the nodal finish
/// 3.41 against 3.33, 2.71 against 2.72 and 1.10 against 1.10, which the 2 % this test asks
/// fails). Hard plucks and soft ones: the contact cases differ.
#[test]
fn the_nodal_contact_plays_what_the_point_contact_plays() {
    use javari_core::tanpura::excitation::Pluck;
    use javari_core::tanpura::modal::GridModes;
    let seed_hz = FdString::new(FdStringConfig::REFERENCE).linearised_fundamental_hz();
    for (key, amplitude_scale) in [(51u8, 1.0), (60, 1.0), (60, 0.05)] {
        let scale = note_to_hz(key) / seed_hz;
        let play = |condensed: bool| {
            let mut config = ModalStringConfig::REFERENCE;
            config.string.tension_n *= scale * scale;
            config.grid_modes = Some(GridModes {
                condensed,
                ..reference_grid_modes(SAMPLE_RATE)
            });
            config.bridge_point_spacing_m = 0.18e-3;
            config.thread_point_spacing_m = 0.15e-3;
            let mut string = ModalString::<f64>::new(config);
            assert_eq!(string.contact_node_count() > 0, condensed);
            let pluck = Pluck::default();
            string.pluck(&Pluck {
                amplitude_m: pluck.amplitude_m * amplitude_scale,
                ..pluck
            });
            let forces: Vec<[f64; 2]> = (0..(0.3 * SAMPLE_RATE) as usize)
                .map(|_| {
                    string.step();
                    [string.nut_force_change_n(), string.bridge_force_change_n()]
                })
                .collect();
            (forces, string.newton_stats().mean_iterations())
        };
        let (points, point_updates) = play(false);
        let (nodes, node_updates) = play(true);
        for pickup in 0..2 {
            let range = points.iter().map(|f| f[pickup].abs()).fold(0.0, f64::max);
            let worst = points
                .iter()
                .zip(&nodes)
                .map(|(p, n)| (p[pickup] - n[pickup]).abs())
                .fold(0.0, f64::max);
            assert!(
                worst <= 1e-9 * range,
                "key {key}, amplitude ×{amplitude_scale}, pickup {pickup}: nodal and point \
                 solves part by {worst:e} N of {range:e} N"
            );
        }
        assert!(
            node_updates <= 0.98 * point_updates,
            "key {key}: {node_updates} updates per step on the nodes, {point_updates} on the points"
        );
    }
}

/// The fine tier's string is the seed's FD scheme in space. Its contact points are the
/// reference's barrier points (every bridge point from the first the string can reach, every
/// thread point), and at the FD's own time step (the reference's, a quarter of the output sample)
/// the two strings play the same pluck. Key 63's softest pluck at 0.20 m is the playing range's
/// most sensitive (`docs/modal-tanpura.md` §10, stop 50): there the seed's grid feeds the 4th
/// partial through the crest's grazing contact by 19 dB over 1.5 s with its own points, and not
/// with the bridge's points half a spacing (0.09 mm) away. Measured over 0.5 s: the nut forces'
/// RMS difference 6.1e-3 of the FD's RMS on the same points, 0.12 with the bridge's points
/// moved by 0.09 mm. The test asks at most 1e-2, and ten times as much for the
/// moved points, so that it fails if the tier's points leave the reference's lattice, if the
/// grid modes part from the FD scheme (their modes, stencils or contact law), or if the points
/// stop mattering.
#[test]
fn the_fine_string_on_the_reference_points_plays_the_fd_string() {
    use javari_core::analysis::playing_range::GridPoint;
    use javari_core::analysis::refined::grid_pluck;
    use javari_core::tanpura::quality::Quality;
    let point = GridPoint {
        key: 63,
        velocity: 1,
        pluck_position_m: 0.20,
    };
    let (settings, pluck) = grid_pluck(Quality::Reference, &point);
    let fd_config = settings
        .fd_config_at(Quality::Reference, SAMPLE_RATE)
        .expect("the reference tier is an FD tier");
    let oversample = (1.0 / (fd_config.time_step_s * SAMPLE_RATE)).round();
    let steps = (0.5 / fd_config.time_step_s) as usize;
    let mut fd = FdString::new(fd_config);
    let fd_points: Vec<f64> = [fd.bridge_grid(), fd.thread_grid()]
        .iter()
        .flat_map(|grid| grid.positions_m().to_vec())
        .collect();
    fd.pluck(&pluck);
    let fd_nut: Vec<f64> = (0..steps)
        .map(|_| {
            fd.step();
            fd.nut_force_n() - fd.rest_nut_force_n()
        })
        .collect();
    let rms = |values: &mut dyn Iterator<Item = f64>| {
        let (sum, count) = values.fold((0.0, 0usize), |(s, n), v| (s + v * v, n + 1));
        (sum / count as f64).sqrt()
    };
    let fd_rms = rms(&mut fd_nut.iter().copied());
    let mut fine = settings;
    fine.quality = Quality::Fine;
    let tier_config = fine
        .modal_config_at(Quality::Fine, SAMPLE_RATE)
        .expect("the fine tier is modal");
    let tier_string = ModalString::<f32>::new(tier_config);
    for x in tier_string.point_positions_m() {
        assert!(
            fd_points.iter().any(|fd_x| (fd_x - x).abs() < 1e-12),
            "the fine tier's point at {x} m is not one of the reference's"
        );
    }
    let play = |bridge_shift_m: f64| {
        let mut config = fine
            .modal_config_at(Quality::Fine, SAMPLE_RATE * oversample)
            .expect("the fine tier is modal");
        config.grid_modes = tier_config.grid_modes;
        config.string = fd_config.string;
        config.bridge.start_m += bridge_shift_m;
        let mut modal = ModalString::<f64>::new(config);
        modal.pluck(&pluck);
        let mut differences = fd_nut.iter().map(|fd_nut| {
            modal.step();
            modal.nut_force_change_n() - fd_nut
        });
        rms(&mut differences) / fd_rms
    };
    let half_spacing_m = 0.5 * tier_config.bridge_point_spacing_m;
    let (same_points, moved_points) = (play(0.0), play(half_spacing_m));
    println!("same points {same_points:e}, moved points {moved_points:e}");
    assert!(
        same_points <= 1e-2,
        "on the reference's points the grid modes part from the FD string by {same_points} of its RMS"
    );
    assert!(
        moved_points >= 10.0 * same_points,
        "points moved by half a spacing part by {moved_points}, on the same points {same_points}"
    );
}

/// The grid modes are the seed's FD scheme in another basis, not an approximation of it. At the
/// FD's own step, on the reference's barrier points and with Newton held to the reference's
/// tolerance, the modal string in f64 steps the FD string's own iterates: after the seed's pluck
/// both strings' displacements at every grid node agree to round-off step after step (measured,
/// stop 60: at most 9.8e-14 of the pluck's largest motion over the first 128 steps; the test
/// asks 1e-12). The continuous string's modes on the same points rest 1.1e-2 of the motion away
/// (the test asks at least 1e-3), so that it fails if the grid modes' poles, shapes or contact
/// leave the FD's. (From about step 185 a difference at the thread's node grows by about 1.5
/// per step and settles near 0.1 µm by step 256, 5e-5 of the motion at step 4096; what starts
/// it was not examined. Over longer spans the 0.5 s nut-force comparison above holds the grid
/// modes to the FD string.)
#[test]
fn the_grid_modes_step_the_fd_schemes_own_iterates() {
    use javari_core::newton::NewtonSettings;
    let fd_config = FdStringConfig::REFERENCE;
    let grid_config = ModalStringConfig {
        bridge_point_spacing_m: 0.18e-3,
        thread_point_spacing_m: 0.15e-3,
        time_step_s: fd_config.time_step_s,
        newton: NewtonSettings::REFERENCE,
        string: fd_config.string,
        ..on_the_grid(ModalStringConfig::REFERENCE)
    };
    assert_eq!(
        grid_config.grid_modes.map(|grid| grid.time_step_s),
        Some(fd_config.time_step_s),
        "the grid modes take the poles of the FD's own step"
    );
    let continuous_config = ModalStringConfig {
        grid_modes: None,
        ..grid_config
    };
    let pluck = javari_core::tanpura::excitation::Pluck::default();
    let nodes = fd_config.intervals;
    let spacing_m = fd_config.string.length_m / nodes as f64;
    // The largest node difference over `steps` steps, relative to the FD string's largest motion.
    let worst_relative_difference = |config: ModalStringConfig, steps: usize| {
        let mut fd = FdString::new(fd_config);
        let mut modal = ModalString::<f64>::new(config);
        fd.pluck(&pluck);
        modal.pluck(&pluck);
        let (mut worst, mut motion) = (0.0f64, 0.0f64);
        for step in 0..=steps {
            if step > 0 {
                fd.step();
                modal.step();
            }
            let (y, rest) = (fd.displacement_m(), fd.rest_displacement_m());
            for i in 1..nodes {
                let modal_y = modal.displacement_at_m(i as f64 * spacing_m);
                worst = worst.max((y[i] - modal_y).abs());
                motion = motion.max((y[i] - rest[i]).abs());
            }
        }
        worst / motion
    };
    let grid = worst_relative_difference(grid_config, 128);
    let continuous = worst_relative_difference(continuous_config, 0);
    println!("grid modes {grid:e}, continuous modes {continuous:e} of the motion");
    assert!(
        grid <= 1e-12,
        "the grid modes part from the FD's iterates by {grid:e} of the motion"
    );
    assert!(
        continuous >= 1e-3,
        "the continuous modes lie only {continuous:e} of the motion from the FD string"
    );
}
