//! The optimised bowed voices against plain per-sample references (house style 12).
//!
//! The voices split delays once per control change, keep mirrored power-of-two histories, skip
//! the friction quadratic while the contact stays stuck, skip the bow table's division on its
//! plateau, filter the body resonances four lanes at a time and render blocks with their state
//! in registers. The references below do none of that: the outgoing waves are kept in growing
//! vectors indexed by sample number, delays are split with `floor` every sample, the friction
//! quadratic is solved every sample, the bow table is `powf(−4)`, the body is one biquad after
//! another from the cookbook formula. Outputs must agree to round-off (1e−12 of the peak);
//! `process` must reproduce `next_sample` bit for bit.

use javari_core::bowed::{
    BowTableString, BowedCapacity, BowedString, BowedVoice, ContactState, FrictionLaw,
    HyperbolicFriction, StringConstants, VIOLIN_BODY,
};

/// One scene: steady controls, then at `change_at` a new force, velocity, position and pitch.
#[derive(Clone, Copy, Debug)]
struct Scene {
    sample_rate_hz: f64,
    pitch_hz: f64,
    bow_position: f64,
    bow_force_n: f64,
    body: bool,
}

const SAMPLES: usize = 30_000;
const CHANGE_AT: usize = 17_000;

const SCENES: [Scene; 3] = [
    // The `cargo xtask bench` note.
    Scene {
        sample_rate_hz: 44_100.0,
        pitch_hz: 220.0,
        bow_position: 0.1,
        bow_force_n: 0.4,
        body: true,
    },
    Scene {
        sample_rate_hz: 48_000.0,
        pitch_hz: 440.0,
        bow_position: 0.13,
        bow_force_n: 0.3,
        body: false,
    },
    Scene {
        sample_rate_hz: 96_000.0,
        pitch_hz: 196.0,
        bow_position: 0.07,
        bow_force_n: 1.0,
        body: true,
    },
];

fn set_controls<V: BowedVoice>(voice: &mut V, scene: &Scene, changed: bool) {
    if changed {
        voice.set_bow_force_n(scene.bow_force_n * 1.3);
        voice.set_bow_velocity_m_s(-0.15);
        voice.set_bow_position(scene.bow_position * 1.7);
        voice.set_pitch_hz(scene.pitch_hz * 1.1);
    } else {
        voice.set_pitch_hz(scene.pitch_hz);
        voice.set_bow_position(scene.bow_position);
        voice.set_bow_velocity_m_s(0.1);
        voice.set_bow_force_n(scene.bow_force_n);
    }
}

/// The violin body as plain biquads, one after another, from the cookbook band-pass.
struct PlainBody {
    /// b0, b2, a1, a2, s1, s2 per resonance.
    sections: Vec<[f64; 6]>,
}

impl PlainBody {
    fn new(sample_rate_hz: f64) -> Self {
        let sections = VIOLIN_BODY
            .iter()
            .map(|resonance| {
                let omega = 2.0 * std::f64::consts::PI * resonance.frequency_hz / sample_rate_hz;
                let alpha = omega.sin() / (2.0 * resonance.quality);
                let a0 = 1.0 + alpha;
                let b0 = resonance.gain_per_n * alpha / a0;
                [
                    b0,
                    -b0,
                    -2.0 * omega.cos() / a0,
                    (1.0 - alpha) / a0,
                    0.0,
                    0.0,
                ]
            })
            .collect();
        Self { sections }
    }

    fn tick(&mut self, x: f64) -> f64 {
        let mut sum = 0.0;
        for [b0, b2, a1, a2, s1, s2] in &mut self.sections {
            let y = *b0 * x + *s1;
            *s1 = -*a1 * y + *s2;
            *s2 = *b2 * x - *a2 * y;
            sum += y;
        }
        sum
    }
}

/// The value pushed `delay` samples before sample `n` (zero before the start).
fn past(history: &[f64], n: usize, delay: usize) -> f64 {
    n.checked_sub(delay).map_or(0.0, |index| history[index])
}

/// Linear interpolation `delay` (fractional) samples before sample `n`, split every call.
fn past_fractional(history: &[f64], n: usize, delay: f64) -> f64 {
    let whole = delay.floor();
    let fraction = delay - whole;
    let newer = past(history, n, whole as usize);
    let older = past(history, n, whole as usize + 1);
    newer + fraction * (older - newer)
}

/// The rounded-corner voice, written out from the module doc of `bowed_string.rs`.
fn reference_rounded(scene: &Scene) -> Vec<f64> {
    let constants = StringConstants::violin_a();
    let z0 = constants.wave_impedance_n_s_m();
    let law = HyperbolicFriction::default();
    // The voice is asked only for its reflection functions (the pulse design has its own tests).
    let mut design = BowedString::new(BowedCapacity::default(), constants);
    design.prepare(scene.sample_rate_hz).unwrap();
    let mut body = PlainBody::new(scene.sample_rate_hz);
    let mut to_bridge = Vec::with_capacity(SAMPLES);
    let mut to_nut = Vec::with_capacity(SAMPLES);
    let mut state = ContactState::Sticking;
    let mut output = Vec::with_capacity(SAMPLES);
    let (mut force, mut velocity) = (0.0, 0.0);
    for n in 0..SAMPLES {
        if n == 0 || n == CHANGE_AT {
            set_controls(&mut design, scene, n == CHANGE_AT);
            force = if n == 0 {
                scene.bow_force_n
            } else {
                scene.bow_force_n * 1.3
            };
            velocity = if n == 0 { 0.1 } else { -0.15 };
        }
        let bridge = design.bridge_reflection();
        let nut = design.nut_reflection();
        let incoming = |history: &[f64], taps: &[f64], first: usize| {
            let mut sum = 0.0;
            for (j, tap) in taps.iter().enumerate() {
                sum += tap * past(history, n, first + j);
            }
            sum
        };
        let incoming_bridge = incoming(&to_bridge, bridge.taps(), bridge.first_tap_delay());
        let incoming_nut = incoming(&to_nut, nut.taps(), nut.first_tap_delay());
        let free_velocity = incoming_bridge + incoming_nut;

        // The bow point with hysteresis, the quadratic solved every sample.
        let a = 2.0 * z0;
        let free_relative = free_velocity - velocity;
        let sticking_force = -a * free_relative;
        let can_stick = sticking_force.abs() <= law.static_coefficient() * force;
        let direction = if free_relative < 0.0 { -1.0 } else { 1.0 };
        let outer = law.outer_slip_speed(a, free_relative.abs(), force);
        let friction_force = match (state, can_stick, outer) {
            (ContactState::Sticking, true, _) | (_, true, None) => {
                state = ContactState::Sticking;
                sticking_force
            }
            (_, _, Some(w)) => {
                state = ContactState::Slipping;
                a * (direction * w - free_relative)
            }
            (_, false, None) => unreachable!("the hyperbolic law always meets the line"),
        };
        let bow_wave = friction_force / a;

        let arriving = past_fractional(&to_bridge, n, bridge.delay_samples());
        to_bridge.push(incoming_nut + bow_wave);
        to_nut.push(incoming_bridge + bow_wave);
        let bridge_force = z0 * (arriving - incoming_bridge);
        output.push(if scene.body {
            body.tick(bridge_force)
        } else {
            bridge_force
        });
    }
    output
}

/// The STK bow-table voice, written out from seed 004 and the module doc of `bow_table.rs`.
fn reference_table(scene: &Scene) -> Vec<f64> {
    let z0 = StringConstants::violin_a().wave_impedance_n_s_m();
    let mut body = PlainBody::new(scene.sample_rate_hz);
    let mut neck = Vec::with_capacity(SAMPLES);
    let mut bridge = Vec::with_capacity(SAMPLES);
    let mut filter_history = [0.0; 2];
    let mut output = Vec::with_capacity(SAMPLES);
    let (mut force, mut velocity, mut beta, mut pitch) = (0.0, 0.0, 0.0, 0.0);
    for n in 0..SAMPLES {
        if n == 0 {
            (force, velocity, beta, pitch) =
                (scene.bow_force_n, 0.1, scene.bow_position, scene.pitch_hz);
        }
        if n == CHANGE_AT {
            (force, velocity, beta, pitch) = (
                scene.bow_force_n * 1.3,
                -0.15,
                scene.bow_position * 1.7,
                scene.pitch_hz * 1.1,
            );
        }
        // One sample of the loop is the loss filter's group delay.
        let line_total = scene.sample_rate_hz / pitch - 1.0;
        let slope = 5.0 - 4.0 * (force / 2.0).clamp(0.0, 1.0);

        let arriving = past_fractional(&bridge, n, beta * line_total);
        let [previous, before_previous] = filter_history;
        let filtered = 0.95 * (0.25 * (arriving + before_previous) + 0.5 * previous);
        filter_history = [arriving, previous];
        let bridge_reflection = -filtered;
        let nut_reflection = -past_fractional(&neck, n, (1.0 - beta) * line_total);
        let differential = velocity - (bridge_reflection + nut_reflection);
        let table = (differential.abs() * slope + 0.75).powf(-4.0).min(1.0);
        let bow_wave = differential * table;
        neck.push(bridge_reflection + bow_wave);
        bridge.push(nut_reflection + bow_wave);
        let bridge_force = z0 * (arriving - bridge_reflection);
        output.push(if scene.body {
            body.tick(bridge_force)
        } else {
            bridge_force
        });
    }
    output
}

fn render<V: BowedVoice>(voice: &mut V, scene: &Scene) -> Vec<f64> {
    voice.prepare(scene.sample_rate_hz).unwrap();
    voice.set_body_enabled(scene.body);
    (0..SAMPLES)
        .map(|n| {
            if n == 0 || n == CHANGE_AT {
                set_controls(voice, scene, n == CHANGE_AT);
            }
            voice.next_sample().radiated
        })
        .collect()
}

/// The same scene through `process`, in blocks of irregular lengths.
fn render_blocks<V: BowedVoice>(voice: &mut V, scene: &Scene) -> Vec<f32> {
    voice.prepare(scene.sample_rate_hz).unwrap();
    voice.set_body_enabled(scene.body);
    set_controls(voice, scene, false);
    let mut output = vec![0.0f32; SAMPLES];
    let lengths = [1, 7, 64, 33, 128, 5, 512];
    let mut start = 0;
    for length in lengths.iter().cycle() {
        if start == SAMPLES {
            break;
        }
        let end = if start < CHANGE_AT {
            (start + length).min(CHANGE_AT)
        } else {
            (start + length).min(SAMPLES)
        };
        voice.process(&mut output[start..end]);
        start = end;
        if start == CHANGE_AT {
            set_controls(voice, scene, true);
        }
    }
    output
}

fn assert_close(voice: &[f64], reference: &[f64], what: &str) {
    let peak = reference.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(peak > 1e-3, "{what}: the scene must sound (peak {peak})");
    for (n, (v, r)) in voice.iter().zip(reference).enumerate() {
        assert!(
            (v - r).abs() <= 1e-12 * peak,
            "{what}: sample {n}: {v} vs reference {r} (peak {peak})"
        );
    }
}

#[test]
fn rounded_corner_matches_the_plain_reference() {
    for scene in &SCENES {
        let mut voice = BowedString::new(BowedCapacity::default(), StringConstants::violin_a());
        let output = render(&mut voice, scene);
        assert_close(&output, &reference_rounded(scene), &format!("{scene:?}"));
    }
}

#[test]
fn bow_table_matches_the_plain_reference() {
    for scene in &SCENES {
        let mut voice = BowTableString::new(BowedCapacity::default(), StringConstants::violin_a());
        let output = render(&mut voice, scene);
        assert_close(&output, &reference_table(scene), &format!("{scene:?}"));
    }
}

#[test]
fn process_reproduces_next_sample_bit_for_bit() {
    for scene in &SCENES {
        let capacity = BowedCapacity::default();
        let constants = StringConstants::violin_a();
        let per_sample = render(&mut BowedString::new(capacity, constants), scene);
        let blocks = render_blocks(&mut BowedString::new(capacity, constants), scene);
        for (n, (a, b)) in per_sample.iter().zip(&blocks).enumerate() {
            assert_eq!((*a as f32).to_bits(), b.to_bits(), "rounded {scene:?} {n}");
        }
        let per_sample = render(&mut BowTableString::new(capacity, constants), scene);
        let blocks = render_blocks(&mut BowTableString::new(capacity, constants), scene);
        for (n, (a, b)) in per_sample.iter().zip(&blocks).enumerate() {
            assert_eq!((*a as f32).to_bits(), b.to_bits(), "table {scene:?} {n}");
        }
    }
}

/// Bow positions and pitches whose bridge-side delay is shorter than a run of `process`
/// (16 samples, `bow_table.rs` and `bowed_string.rs`): runs of 4 to 7 samples, and below 4 the
/// sample-by-sample path.
const SHORT_DELAY_SCENES: [Scene; 3] = [
    // 49 samples around the loop, 4.9 of them bow → bridge: runs of 4.
    Scene {
        sample_rate_hz: 44_100.0,
        pitch_hz: 880.0,
        bow_position: 0.1,
        bow_force_n: 0.4,
        body: true,
    },
    // 1.2 samples bow → bridge: sample by sample.
    Scene {
        sample_rate_hz: 44_100.0,
        pitch_hz: 1760.0,
        bow_position: 0.05,
        bow_force_n: 0.4,
        body: true,
    },
    // 7.2 samples, body off.
    Scene {
        sample_rate_hz: 48_000.0,
        pitch_hz: 660.0,
        bow_position: 0.1,
        bow_force_n: 0.6,
        body: false,
    },
];

#[test]
fn runs_reproduce_next_sample_at_short_delays() {
    fn check<V: BowedVoice>(make: impl Fn() -> V, scene: &Scene, what: &str) {
        let per_sample = render(&mut make(), scene);
        let peak = per_sample.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(peak > 1e-3, "{what} {scene:?} must sound (peak {peak})");
        let blocks = render_blocks(&mut make(), scene);
        for (n, (a, b)) in per_sample.iter().zip(&blocks).enumerate() {
            assert_eq!((*a as f32).to_bits(), b.to_bits(), "{what} {scene:?} {n}");
        }
    }
    let capacity = BowedCapacity::default();
    let constants = StringConstants::violin_a();
    for scene in &SHORT_DELAY_SCENES {
        check(|| BowTableString::new(capacity, constants), scene, "table");
        check(|| BowedString::new(capacity, constants), scene, "rounded");
    }
}
