//! Invariants of the modal tanpura scheme (`core/src/tanpura/modal/`, `docs/modal-tanpura.md`):
//! the discrete energy balance of eq. M3 in contact (lossless conserved, lossy balanced, H never
//! rising), exact partial frequencies and decay rates in the running string, rest contact depth,
//! a bounded Newton iteration, determinism, and the f32 tier's agreement with the f64 path.

use javari_core::analysis::refined::reference_grid_modes;
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::modal::{GridModes, ModalString, ModalStringConfig};
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::VoiceSettings;

const SAMPLE_RATE: f64 = 44_100.0;
const DIAMETER_M: f64 = 0.3e-3;

fn plucked<T: javari_core::tanpura::modal::lanes::Real>(
    config: ModalStringConfig,
) -> ModalString<T> {
    let mut string = ModalString::<T>::new(config);
    string.pluck(&Pluck::default());
    string
}

/// With and without the truncated modes' static flexibility (which moves the rest state, not
/// the scheme), with residual modes (more modes of the same recursion), and with the reference
/// grid's 199 modes (section 10, those above Nyquist included), the contact solved on the points
/// or condensed on the grid's nodes (section 11, also with points as fine as the reference's
/// barrier grids), the lossless H is conserved.
#[test]
fn lossless_energy_is_conserved_to_1e_10_in_contact() {
    for (flexible, residual_modes, grid) in [
        (true, 0, None),
        (false, 0, None),
        (false, 2, None),
        (false, 0, Some((false, false))),
        (false, 0, Some((true, false))),
        (false, 0, Some((true, true))),
    ] {
        let mut config = ModalStringConfig::REFERENCE.lossless();
        config.track_energy = true;
        config.static_flexibility = flexible;
        config.residual_modes = residual_modes;
        if let Some((condensed, fine)) = grid {
            config = on_the_grid(config, condensed, fine);
        }
        let mut string = plucked::<f64>(config);
        if let Some((condensed, _)) = grid {
            assert_eq!(
                string.modes().count(),
                199,
                "every mode of the 200-interval grid"
            );
            assert_eq!(string.contact_node_count() > 0, condensed);
        }
        let worst = lossless_drift(&mut string, SAMPLE_RATE as usize);
        let stats = *string.newton_stats();
        assert!(
            stats.steps_without_contact < stats.steps / 10,
            "the balance is tested in contact: {stats:?}"
        );
        assert_eq!(string.cumulative_losses_j(), 0.0);
        assert!(
            worst <= 1e-10,
            "relative energy drift {worst:e} (flexible: {flexible}, residual modes: \
             {residual_modes}, grid modes (condensed, fine points): {grid:?})"
        );
    }
}

/// Runs a lossless `string` for `steps` steps: the largest relative departure of H from its
/// value before the first.
fn lossless_drift(string: &mut ModalString<f64>, steps: usize) -> f64 {
    let initial = string.energy_j();
    let mut worst = 0.0f64;
    for _ in 0..steps {
        string.step();
        worst = worst.max((string.energy_j() - initial).abs() / initial);
    }
    worst
}

/// `config` on the reference's grid modes (section 10), the contact solved on the points or
/// condensed on the nodes (section 11), with the reference's barrier spacings if `fine`.
fn on_the_grid(mut config: ModalStringConfig, condensed: bool, fine: bool) -> ModalStringConfig {
    config.grid_modes = Some(GridModes {
        condensed,
        ..reference_grid_modes(SAMPLE_RATE)
    });
    if fine {
        config.bridge_point_spacing_m = 0.18e-3;
        config.thread_point_spacing_m = 0.15e-3;
    }
    config
}

/// Plucks a string of `config` (losses booked) and runs it for `seconds`; returns it with the
/// largest rise of H in one step and the largest departure from `H + losses = H₀`, both relative
/// to H₀.
fn lossy_run(config: ModalStringConfig, seconds: f64) -> (ModalString<f64>, f64, f64) {
    let mut string = plucked::<f64>(config);
    let initial = string.energy_j();
    let mut previous = initial;
    let (mut worst_increase, mut worst_balance) = (0.0f64, 0.0f64);
    for _ in 0..(seconds * SAMPLE_RATE) as usize {
        string.step();
        let energy = string.energy_j();
        worst_increase = worst_increase.max((energy - previous) / initial);
        worst_balance =
            worst_balance.max((energy + string.cumulative_losses_j() - initial).abs() / initial);
        previous = energy;
    }
    (string, worst_increase, worst_balance)
}

/// Residual modes (two, as the example `crest_contact` runs them): the lossy balance holds, and
/// the string rests on the bridge crest and settles onto it as the continuous string does, where
/// the kept modes alone leave it above the crest, striking it to the end of the note.
#[test]
fn residual_modes_keep_the_balance_and_let_the_string_settle_on_the_crest() {
    let mut config = ModalStringConfig::REFERENCE;
    config.track_energy = true;
    config.residual_modes = 2;
    let (_, worst_increase, worst_balance) = lossy_run(config, 0.5);
    assert!(
        worst_increase <= 1e-14,
        "H increased by {worst_increase:e} of H(0)"
    );
    assert!(worst_balance <= 1e-10, "balance error {worst_balance:e}");

    // Landings on the bridge (a step with a bridge point in contact after one with none) in
    // 2.0–2.5 s after the pluck, and the deepest bridge gap at rest.
    let settle = |residual_modes: usize| {
        let mut string = ModalString::<f32>::new(ModalStringConfig {
            residual_modes,
            ..ModalStringConfig::REFERENCE
        });
        let bridge = string.bridge_point_count();
        let deepest_at_rest = string.gaps_m()[..bridge]
            .iter()
            .cloned()
            .fold(f64::MIN, f64::max);
        string.pluck(&Pluck::default());
        let (mut landings, mut was_in_contact) = (0, false);
        for step in 0..(2.5 * SAMPLE_RATE) as usize {
            string.step();
            let in_contact = string.gaps_m()[..bridge].iter().any(|&gap| gap > 0.0);
            if step as f64 >= 2.0 * SAMPLE_RATE && in_contact && !was_in_contact {
                landings += 1;
            }
            was_in_contact = in_contact;
        }
        (deepest_at_rest, landings)
    };
    let (kept_rest, kept_landings) = settle(0);
    let (residual_rest, residual_landings) = settle(2);
    assert!(
        kept_rest < -5e-6,
        "kept modes alone: {kept_rest:e} m at rest"
    );
    assert!(
        kept_landings > 500,
        "kept modes alone: {kept_landings} landings"
    );
    assert!(
        residual_rest > 0.0,
        "residual modes: {residual_rest:e} m at rest"
    );
    assert_eq!(
        residual_landings, 0,
        "residual modes: the string still strikes the crest"
    );
}

/// Grid modes (section 10): the lossy balance holds with every mode of the reference's grid,
/// the contact solved on the points or condensed on the nodes (section 11).
#[test]
fn grid_modes_keep_the_lossy_balance() {
    for (condensed, fine) in [(false, false), (true, false), (true, true)] {
        let mut config = on_the_grid(ModalStringConfig::REFERENCE, condensed, fine);
        config.track_energy = true;
        let (string, worst_increase, worst_balance) = lossy_run(config, 0.5);
        let case = format!("condensed: {condensed}, fine points: {fine}");
        assert_eq!(string.contact_node_count() > 0, condensed, "{case}");
        assert!(string.cumulative_losses_j() > 0.0, "{case}");
        assert!(
            worst_increase <= 1e-14,
            "H increased by {worst_increase:e} of H(0) ({case})"
        );
        assert!(
            worst_balance <= 1e-10,
            "balance error {worst_balance:e} ({case})"
        );
        assert_eq!(string.newton_stats().cap_hits, 0, "{case}");
    }
}

#[test]
fn lossy_energy_balance_holds_h_never_rises_and_newton_stays_under_its_cap() {
    let mut config = ModalStringConfig::REFERENCE;
    config.track_energy = true;
    let (string, worst_increase, worst_balance) = lossy_run(config, 2.0);
    let stats = *string.newton_stats();
    let vibration = string.energy_j() + string.cumulative_losses_j() - string.rest_energy_j();
    assert!(string.cumulative_losses_j() > 0.1 * vibration);
    assert!(
        worst_increase <= 1e-14,
        "H increased by {worst_increase:e} of H(0)"
    );
    assert!(worst_balance <= 1e-10, "balance error {worst_balance:e}");
    assert_eq!(stats.cap_hits, 0, "{stats:?}");
    assert!(stats.max_iterations <= 10, "{stats:?}");
    // 1.41 updates per step when the exact finish solved only the crossing case, 1.16 with
    // both cases (`block::exact_crossing_step`).
    let mean = stats.iterations as f64 / stats.steps as f64;
    assert!(mean <= 1.25, "{mean:.3} Newton updates per step: {stats:?}");
}

/// With contact 100 times stiffer than the seed's (k_b = k_c = 1e10 N/m²), points enter and
/// leave contact with large forces over tiny penetrations, where Newton alone converges slowly:
/// 3.76 updates per step here without the exact finish of `ContactStep::finish_exactly` (as
/// measured when it was introduced); 1.64 with a finish that solves only the crossing case (11 at
/// most in one step), 1.28 with one that also solves the case the point had (4 at most). The
/// exact finish must keep the lossy balance to round-off and bring the mean under 1.4 updates
/// per step.
#[test]
fn stiff_contact_keeps_the_balance_and_newton_stays_short() {
    let mut config = ModalStringConfig::REFERENCE;
    config.track_energy = true;
    config.bridge.stiffness_n_m2 = 1e10;
    if let Some(thread) = config.thread.as_mut() {
        thread.stiffness_n_m2 = 1e10;
    }
    let (string, worst_increase, worst_balance) = lossy_run(config, 1.0);
    let stats = *string.newton_stats();
    assert!(
        worst_increase <= 1e-14,
        "H increased by {worst_increase:e} of H(0)"
    );
    assert!(worst_balance <= 1e-10, "balance error {worst_balance:e}");
    assert_eq!(stats.cap_hits, 0, "{stats:?}");
    let mean = stats.iterations as f64 / stats.steps as f64;
    assert!(mean <= 1.4, "{mean:.2} Newton updates per step: {stats:?}");
}

/// Each mode of the running string obeys `r(n+1) = 2R cos(ω_d Δt) r(n) − R² r(n−1)`,
/// `R = e^{−σΔt}`, `ω_d = √(ω² − σ²)`: the sampled free decay of the continuous mode, so its
/// frequency and decay rate are exact. Checked away from contact (no bridge, no thread), where
/// nothing else drives the modes.
#[test]
fn free_modes_ring_at_the_exact_frequencies_and_decay_rates() {
    let mut config = ModalStringConfig::REFERENCE;
    config.bridge.stiffness_n_m2 = 0.0;
    config.thread = None;
    config.string.eta_s = 2e-7;
    let mut string = ModalString::<f64>::new(config);
    string.excite_first_mode(1e-3);
    // Give every mode some amplitude: the first mode of the speaking length projects on all.
    let dt = config.time_step_s;
    let modes = string.modes().clone();
    let count = modes.count();
    assert!(count > 50, "{count} modes");
    let mut history: Vec<Vec<f64>> = Vec::new();
    for _ in 0..2000 {
        string.step();
        history.push(string.modal_state().0.to_vec());
    }
    for k in [0, 1, 4, 9, count / 2, count - 1] {
        let omega = modes.angular_frequency[k];
        let sigma = modes.decay[k];
        let radius = (-sigma * dt).exp();
        let damped = (omega * omega - sigma * sigma).sqrt();
        let twice_cos = 2.0 * radius * (damped * dt).cos();
        let scale = history.iter().map(|r| r[k].abs()).fold(0.0, f64::max);
        assert!(scale > 0.0, "mode {k} is excited");
        let worst = history
            .windows(3)
            .map(|w| (w[2][k] - twice_cos * w[1][k] + radius * radius * w[0][k]).abs())
            .fold(0.0, f64::max);
        assert!(
            worst <= 1e-12 * scale,
            "mode {k} ({:.1} Hz): recurrence residual {worst:e} of {scale:e}",
            omega / (2.0 * std::f64::consts::PI)
        );
        // σ = γ/2 + ηω²/2 (seed 000, eq. 6).
        let expected = 0.5 * config.string.gamma_per_s + 0.5 * config.string.eta_s * omega * omega;
        assert!((sigma - expected).abs() <= 1e-12 * expected);
    }
}

/// The stiff string's frequency of mode `number` (seed 000, eq. 5 with simply supported ends).
fn mode_frequency_hz(config: &ModalStringConfig, number: usize) -> f64 {
    let p = config.string;
    let beta = number as f64 * std::f64::consts::PI / p.length_m;
    let omega2 = (p.tension_n * beta * beta + p.bending_stiffness_n_m2 * beta.powi(4))
        / p.linear_density_kg_m;
    omega2.sqrt() / (2.0 * std::f64::consts::PI)
}

/// Every mode below min(20 kHz, 0.45 f_s) is kept and none above, at every rate and down to a
/// nearly slack string: stiffness alone puts mode 122 above 20 kHz, so the capacity (128) is
/// never what limits the count.
#[test]
fn modes_are_kept_below_20_khz_and_below_nyquist() {
    for rate in [22_050.0, 44_100.0, 96_000.0, 192_000.0] {
        for tension in [0.01, 31.47, 2000.0] {
            let mut config = ModalStringConfig {
                time_step_s: 1.0 / rate,
                ..ModalStringConfig::REFERENCE
            };
            config.string.tension_n = tension;
            let string = ModalString::<f32>::new(config);
            let count = string.modes().count();
            let limit = (20_000.0f64).min(0.45 * rate);
            assert!(
                mode_frequency_hz(&config, count) < limit,
                "{rate} Hz, T = {tension}"
            );
            assert!(
                mode_frequency_hz(&config, count + 1) >= limit,
                "{rate} Hz, T = {tension}: {count} modes"
            );
            assert!(count < javari_core::tanpura::modal::modes::MODE_CAPACITY);
        }
    }
}

#[test]
fn string_at_rest_sits_on_the_thread_and_penetrates_under_five_percent_of_diameter() {
    let string = ModalString::<f32>::new(ModalStringConfig::REFERENCE);
    let points = string.points();
    let gaps = string.gaps_m();
    let thread = points.bridge_count()..points.len();
    assert!(
        gaps[thread.clone()].iter().any(|&a| a > 0.0),
        "on the thread"
    );
    let deepest = gaps.iter().cloned().fold(0.0, f64::max);
    assert!(deepest < 0.05 * DIAMETER_M, "{deepest:e} m");
    assert!(string.rest_bridge_force_n() > 0.0);
    assert_eq!(string.static_solve_failures(), 0);
    // The rest shape follows the thread's top within the penetration.
    let top = points.positions_m[thread.start + thread.len() / 2];
    let height = points.heights_m[thread.start + thread.len() / 2];
    assert!((string.rest_displacement_at_m(top) - height).abs() < 0.05 * DIAMETER_M);
}

/// The deepest penetration while ringing is on the thread's top, 15.7–15.9 µm for point
/// spacings from 0.25 to 1 mm (converged in the spacing; the FD reference grid gives under
/// 15 µm): under 6 % of the diameter.
#[test]
fn penetration_stays_under_six_percent_of_diameter_while_ringing() {
    let mut string = plucked::<f32>(ModalStringConfig::REFERENCE);
    let mut deepest = 0.0f64;
    for _ in 0..(0.2 * SAMPLE_RATE) as usize {
        string.step();
        deepest = deepest.max(string.max_penetration_m());
    }
    assert!(deepest > 0.0);
    assert!(deepest < 0.06 * DIAMETER_M, "{deepest:e} m");
}

#[test]
fn two_runs_are_bit_identical() {
    let run = || {
        let mut string = plucked::<f32>(ModalStringConfig::REFERENCE);
        (0..10_000)
            .map(|_| {
                string.step();
                (
                    string.nut_force_change_n().to_bits(),
                    string.bridge_force_change_n().to_bits(),
                )
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(run(), run());
}

/// The live tier runs its modes in f32: its nut force follows the f64 path's closely over the
/// first 0.2 s of a pluck (contact included).
#[test]
fn f32_modes_follow_the_f64_path() {
    let mut single = plucked::<f32>(ModalStringConfig::REFERENCE);
    let mut double = plucked::<f64>(ModalStringConfig::REFERENCE);
    let (mut error, mut power) = (0.0f64, 0.0f64);
    for _ in 0..(0.2 * SAMPLE_RATE) as usize {
        single.step();
        double.step();
        let (a, b) = (single.nut_force_change_n(), double.nut_force_change_n());
        error += (a - b) * (a - b);
        power += b * b;
    }
    let relative = (error / power).sqrt();
    assert!(power > 0.0);
    assert!(relative < 1e-3, "relative RMS difference {relative:e}");
}

/// `TanpuraVoice::process` (which runs a modal string's steps between sleep checks as one call
/// on the vector unit) gives `next_sample`'s samples bit for bit, in blocks of every size from
/// one sample up, through a pluck, its ringing, the sleep check and the string falling asleep,
/// on every modal tier.
#[test]
fn modal_voice_blocks_equal_its_samples() {
    use javari_core::tanpura::TanpuraVoice;
    for quality in [Quality::Live, Quality::Fine] {
        let settings = VoiceSettings {
            quality,
            // A short decay, so that the string falls asleep within the test.
            gamma_per_s: 20.0,
            ..VoiceSettings::default()
        };
        let mut by_blocks = TanpuraVoice::new(&settings, 44_100.0);
        let mut by_samples = by_blocks.clone();
        by_blocks.pluck(&Pluck::default());
        by_samples.pluck(&Pluck::default());
        let sizes = [1, 7, 64, 255, 256, 257, 1000, 4096];
        let (mut blocks, mut samples) = (Vec::new(), Vec::new());
        for size in sizes.iter().cycle().take(160) {
            let mut block = vec![0.0f32; *size];
            by_blocks.process(&mut block);
            blocks.extend(block.iter().map(|x| x.to_bits()));
            samples.extend((0..*size).map(|_| by_samples.next_sample().to_bits()));
        }
        assert!(blocks == samples, "{quality:?}: blocks part from samples");
        assert!(
            !by_blocks.is_active(),
            "{quality:?}: the string never fell asleep"
        );
        assert!(blocks.iter().any(|&bits| f32::from_bits(bits) != 0.0));
    }
}

/// The residual modes' shapes at the points make `Σ_j ψ_j(x_a) ψ_j(x_b)` the best rank-J part of
/// the truncated modes' compliance `R = C − Ψ_K Ψ_Kᵀ` (`docs/modal-tanpura.md` section 8): the
/// retune's subspace iteration gives what the whole decomposition of R gives, for one to four
/// residual modes at the live tier's points.
#[test]
fn residual_mode_shapes_are_the_leading_part_of_the_truncated_compliance() {
    use javari_core::dense::symmetric_eigen_jacobi;
    use javari_core::tanpura::modal::modes::MODE_CAPACITY;
    for residual_modes in 1..=4 {
        let config = ModalStringConfig {
            residual_modes,
            bridge_point_spacing_m: 2e-3,
            ..ModalStringConfig::REFERENCE
        };
        let string = ModalString::<f32>::new(config);
        let (modes, points) = (string.modes(), string.points());
        let positions = string.point_positions_m();
        let size = positions.len();
        let rows: Vec<Vec<f64>> = positions
            .iter()
            .map(|&x| {
                let mut row = vec![0.0; MODE_CAPACITY];
                modes.shape_row(x, &mut row);
                row
            })
            .collect();
        let mut truncated = vec![0.0; size * size];
        for a in 0..size {
            for b in 0..size {
                truncated[a * size + b] =
                    modes.residual_compliance_m_n(positions[a], positions[b], &rows[a], &rows[b]);
            }
        }
        let mut vectors = vec![0.0; size * size];
        symmetric_eigen_jacobi(&mut truncated, &mut vectors, size, size);
        let mut order: Vec<usize> = (0..size).collect();
        order.sort_by(|&a, &b| truncated[b * size + b].total_cmp(&truncated[a * size + a]));
        let largest = truncated[order[0] * size + order[0]];
        let (kept, count) = (modes.kept(), modes.count());
        assert_eq!(count - kept, residual_modes);
        for a in 0..size {
            for b in 0..size {
                let leading: f64 = order[..residual_modes]
                    .iter()
                    .map(|&e| {
                        truncated[e * size + e] * vectors[a * size + e] * vectors[b * size + e]
                    })
                    .sum();
                let shaped: f64 = (kept..count)
                    .map(|k| points.shape(a)[k] * points.shape(b)[k])
                    .sum();
                assert!(
                    (leading - shaped).abs() <= 1e-10 * largest,
                    "{residual_modes} modes, points {a}, {b}: {leading:e} against {shaped:e}"
                );
            }
        }
    }
}

/// The thread's lattice keeps its points off the rest state's contact edges at every key, so
/// that the contact solve takes about one Newton update per step across the playing range: the
/// live tier's one-string scene (default pluck, linearised tuning) for 0.5 s at every key of
/// 36–64. With the lattice fixed at 0.5 mm on the thread's top, key 59 took 1.620 updates per
/// step (at rest one of its thread points barely touched, 0.005 N, and its neighbour lay 1.1 µm
/// clear); with stop 38's rule (the lattice shifted off the top) the most was 1.181 (key 58);
/// with stop 39's (coarser lattices on the top first) it is 1.071 (key 62). Every key's lattice
/// is checked against the one the docs state (`ModalString::thread_lattice_spacing_m`,
/// `thread_lattice_offset_m`).
#[test]
fn the_thread_lattice_keeps_newton_near_one_update_per_step_at_every_key() {
    use javari_core::engine::pitch::note_to_hz;
    use javari_core::tanpura::tier_string::TierString;
    use javari_core::tanpura::TanpuraVoice;
    let mut worst = (0u8, 0.0f64);
    for key in 36..=64u8 {
        let settings = VoiceSettings {
            quality: Quality::Live,
            fundamental_hz: note_to_hz(key),
            ..VoiceSettings::default()
        };
        let mut voice = TanpuraVoice::new(&settings, SAMPLE_RATE);
        voice.pluck(&Pluck::default());
        let mut block = [0.0f32; 64];
        for _ in 0..(0.5 * SAMPLE_RATE) as usize / 64 {
            voice.process(&mut block);
        }
        let updates = voice.newton_stats().mean_iterations();
        if updates > worst.1 {
            worst = (key, updates);
        }
        if let TierString::Modal(string) = voice.string() {
            let spacing_m = string.thread_lattice_spacing_m();
            eprintln!(
                "key {key}: thread points {:.3} mm apart, {:.3} mm off the top, \
                 {updates:.3} updates per step",
                spacing_m * 1e3,
                string.thread_lattice_offset_m() * 1e3
            );
            // The lattice each key takes, as docs/modal-tanpura.md §3 states it: a
            // coarser one on the top at keys 36 and 58–60 (the configured one there has a point
            // at the contact's edge), the configured one straddling the top at 37–48 and 61–64
            // (no lattice keeps the margin), the configured one at 49–57.
            let expected_mm = match key {
                36 | 58 | 59 => (0.55, 0.0),
                60 => (0.6, 0.0),
                37..=48 | 61..=64 => (0.5, 0.25),
                _ => (0.5, 0.0),
            };
            let taken_mm = (spacing_m * 1e3, string.thread_lattice_offset_m() * 1e3);
            assert!(
                (taken_mm.0 - expected_mm.0).abs() < 1e-9
                    && (taken_mm.1 - expected_mm.1).abs() < 1e-9,
                "key {key}: lattice {taken_mm:?} mm, the documented one {expected_mm:?} mm"
            );
        } else {
            panic!("the live tier is modal");
        }
    }
    eprintln!(
        "most Newton updates per step: {:.3} at key {}",
        worst.1, worst.0
    );
    assert!(
        worst.1 < 1.15,
        "{:.3} updates per step at key {}",
        worst.1,
        worst.0
    );
}

/// A change of the string's losses alone (γ, η) leaves its rest state, and so the thread's
/// lattice, where it was: it costs one static solve, where a change that moves the rest state
/// tries the lattices again (`ModalString::place_thread_lattice`). Keys 40, 59 and 62 of the
/// live tier, where the configured lattice does not keep the margin. The string it leaves is the
/// one built for the new losses: the same lattice and the same rest gaps.
#[test]
fn a_change_of_the_losses_alone_keeps_the_thread_lattice_with_one_static_solve() {
    use javari_core::engine::pitch::note_to_hz;
    for key in [40u8, 59, 62] {
        let settings = VoiceSettings {
            fundamental_hz: note_to_hz(key),
            ..VoiceSettings::default()
        };
        let config = settings
            .modal_config_at(Quality::Live, SAMPLE_RATE)
            .expect("the live tier is modal");
        let mut string = ModalString::<f64>::new(config);
        let built = string.rest_state_solves();
        assert!(built > 1, "key {key}: the configured lattice was kept");
        let mut lossier = config;
        lossier.string.gamma_per_s *= 2.0;
        lossier.string.eta_s *= 1.5;
        assert!(string.set_config(lossier));
        assert_eq!(string.rest_state_solves(), built + 1, "key {key}");
        let fresh = ModalString::<f64>::new(lossier);
        assert_eq!(
            string.thread_lattice_spacing_m(),
            fresh.thread_lattice_spacing_m(),
            "key {key}"
        );
        assert_eq!(
            string.thread_lattice_offset_m(),
            fresh.thread_lattice_offset_m(),
            "key {key}"
        );
        assert_eq!(string.points().len(), fresh.points().len());
        for i in 0..fresh.points().len() {
            let (kept, built) = (
                string.points().rest_gaps_m[i],
                fresh.points().rest_gaps_m[i],
            );
            assert!(
                (kept - built).abs() < 1e-12,
                "key {key}, point {i}: {kept} against {built}"
            );
        }
    }
}

/// The studio tier's own string (`docs/modal-tanpura.md` §13: the fine tier's, stepped at the
/// reference's step, a quarter of the fine tier's): lossless, H is conserved to 1e-10 in
/// contact; lossy, `H + losses = H₀` to 1e-10 and H never rises. A quarter of a second at its
/// step of 1/176 400 s.
#[test]
fn the_studio_tiers_string_keeps_the_balance_at_its_own_step() {
    let config = tier_config(Quality::Studio);
    assert_eq!(config.time_step_s, 0.25 / SAMPLE_RATE);
    // A quarter of a second: as many steps as a second has samples.
    assert_keeps_the_balance(config, SAMPLE_RATE as usize);
}

/// The other modal tiers' own strings, as the voice builds them (`VoiceSettings::modal_config_at`:
/// live's modes below 20 kHz on points every 2 mm of the bridge and 0.5 mm of the thread, fine's
/// grid modes condensed on the nodes at the output rate): the same balance over half a second, in
/// contact at every step. Measured in stop 61 (live / fine): lossless drift 1.5e-13 / 1.7e-13,
/// lossy balance 4.1e-13 / 2.9e-13, H never rising.
#[test]
fn the_live_and_fine_tiers_strings_keep_the_balance() {
    for quality in [Quality::Live, Quality::Fine] {
        let config = tier_config(quality);
        assert_eq!(config.time_step_s, 1.0 / SAMPLE_RATE, "{quality:?}");
        assert_eq!(config.grid_modes.is_some(), quality == Quality::Fine);
        assert_keeps_the_balance(config, (0.5 * SAMPLE_RATE) as usize);
    }
}

/// The string of `quality` at the seed's settings, with its losses booked.
fn tier_config(quality: Quality) -> ModalStringConfig {
    let settings = VoiceSettings {
        quality,
        ..VoiceSettings::default()
    };
    let mut config = settings
        .modal_config_at(quality, SAMPLE_RATE)
        .expect("a modal tier");
    config.track_energy = true;
    config
}

/// Plucked, `config` made lossless keeps H to 1e-10 over `steps` steps in contact, and `config`
/// itself keeps `H + losses = H₀` to 1e-10 with H never rising, Newton never at its cap.
fn assert_keeps_the_balance(config: ModalStringConfig, steps: usize) {
    let mut lossless = plucked::<f64>(config.lossless());
    let worst = lossless_drift(&mut lossless, steps);
    let stats = *lossless.newton_stats();
    assert!(
        stats.steps_without_contact < stats.steps / 10,
        "the balance is tested in contact: {stats:?}"
    );
    assert!(worst <= 1e-10, "lossless: relative energy drift {worst:e}");

    // `lossy_run` takes seconds at the output rate; a step may be shorter than a sample.
    let (string, worst_increase, worst_balance) = lossy_run(config, steps as f64 / SAMPLE_RATE);
    assert!(string.cumulative_losses_j() > 0.0);
    assert!(
        worst_increase <= 1e-14,
        "H increased by {worst_increase:e} of H(0)"
    );
    assert!(worst_balance <= 1e-10, "balance error {worst_balance:e}");
    assert_eq!(string.newton_stats().cap_hits, 0);
}
