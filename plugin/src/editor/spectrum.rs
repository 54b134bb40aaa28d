//! The editor-side analysis of the force strip: a Hann-windowed spectrum of each frame's force
//! history (`javari_core::analysis::fft`), a scrolling spectrogram of the last
//! [`SPECTROGRAM_FRAMES`] frames, and the spectral centroid of the jawari band, whose fall over
//! a note is the formant the seed describes (section 5). Runs on the GUI thread only.

use javari_core::analysis::{fft, hann, spectral_centroid_hz};
use javari_core::snapshot::{TanpuraSnapshot, FORCE_HISTORY_SAMPLES};

/// Frames the spectrogram remembers: 6 s at 50 frames per second.
pub const SPECTROGRAM_FRAMES: usize = 300;
/// Highest frequency shown, Hz.
pub const MAX_SHOWN_HZ: f64 = 8000.0;
/// Rows of the spectrogram image (frequency bins grouped up to [`MAX_SHOWN_HZ`]).
pub const SPECTROGRAM_ROWS: usize = 160;
/// Band of the centroid that tracks the jawari formant, Hz.
pub const FORMANT_BAND_HZ: (f64, f64) = (500.0, 8000.0);
/// Floor of the dB scale relative to the loudest bin seen.
pub const DYNAMIC_RANGE_DB: f64 = 80.0;

/// Spectra of the incoming frames.
pub struct ForceAnalysis {
    window: Vec<f64>,
    re: Vec<f64>,
    im: Vec<f64>,
    /// Power per bin of the newest frame (bins 0..=N/2).
    pub power: Vec<f64>,
    /// Bin width of `power`, Hz.
    pub bin_hz: f64,
    /// dB rows per remembered frame (oldest first once full), row 0 = 0 Hz.
    pub spectrogram_db: Vec<[f32; SPECTROGRAM_ROWS]>,
    /// Centroid of the formant band per remembered frame, Hz (NaN when silent).
    pub centroid_hz: Vec<f64>,
    /// Loudest bin seen, dB (decays slowly so the scale follows the note).
    pub reference_db: f64,
    /// Set when the spectrogram changed since the view last uploaded it.
    pub changed: bool,
}

impl Default for ForceAnalysis {
    fn default() -> Self {
        Self {
            window: hann(FORCE_HISTORY_SAMPLES),
            re: vec![0.0; FORCE_HISTORY_SAMPLES],
            im: vec![0.0; FORCE_HISTORY_SAMPLES],
            power: vec![0.0; FORCE_HISTORY_SAMPLES / 2 + 1],
            bin_hz: 0.0,
            spectrogram_db: Vec::with_capacity(SPECTROGRAM_FRAMES),
            centroid_hz: Vec::with_capacity(SPECTROGRAM_FRAMES),
            reference_db: -200.0,
            changed: false,
        }
    }
}

fn to_db(power: f64) -> f64 {
    10.0 * power.max(1e-30).log10()
}

impl ForceAnalysis {
    /// Analyses the force history of a new frame.
    pub fn update(&mut self, snapshot: &TanpuraSnapshot) {
        let force = snapshot.force_history_n();
        if force.len() < FORCE_HISTORY_SAMPLES || snapshot.sample_rate_hz <= 0.0 {
            return;
        }
        let mean = force.iter().map(|&f| f64::from(f)).sum::<f64>() / force.len() as f64;
        for (i, &f) in force.iter().enumerate() {
            self.re[i] = (f64::from(f) - mean) * self.window[i];
            self.im[i] = 0.0;
        }
        fft(&mut self.re, &mut self.im);
        for (bin, power) in self.power.iter_mut().enumerate() {
            *power = self.re[bin] * self.re[bin] + self.im[bin] * self.im[bin];
        }
        self.bin_hz = snapshot.sample_rate_hz / FORCE_HISTORY_SAMPLES as f64;

        let loudest = self.power.iter().copied().fold(0.0, f64::max);
        self.reference_db = (self.reference_db - 0.5).max(to_db(loudest));
        let mut rows = [0.0f32; SPECTROGRAM_ROWS];
        let shown_bins = ((MAX_SHOWN_HZ / self.bin_hz) as usize).min(self.power.len() - 1);
        for (row, value) in rows.iter_mut().enumerate() {
            let first = row * shown_bins / SPECTROGRAM_ROWS;
            let last = ((row + 1) * shown_bins / SPECTROGRAM_ROWS).max(first + 1);
            let peak = self.power[first..last].iter().copied().fold(0.0, f64::max);
            *value =
                ((to_db(peak) - self.reference_db) / DYNAMIC_RANGE_DB + 1.0).clamp(0.0, 1.0) as f32;
        }
        let centroid = if loudest > 0.0 {
            spectral_centroid_hz(
                &self.power,
                self.bin_hz,
                FORMANT_BAND_HZ.0,
                FORMANT_BAND_HZ.1,
            )
        } else {
            f64::NAN
        };
        if self.spectrogram_db.len() == SPECTROGRAM_FRAMES {
            self.spectrogram_db.remove(0);
            self.centroid_hz.remove(0);
        }
        self.spectrogram_db.push(rows);
        self.centroid_hz.push(centroid);
        self.changed = true;
    }

    /// The newest spectrum as (frequency Hz, level dB relative to the loudest bin seen) up to
    /// [`MAX_SHOWN_HZ`].
    pub fn spectrum_db(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        let bin_hz = self.bin_hz;
        let reference = self.reference_db;
        self.power
            .iter()
            .enumerate()
            .take_while(move |(bin, _)| *bin as f64 * bin_hz <= MAX_SHOWN_HZ)
            .map(move |(bin, &power)| (bin as f64 * bin_hz, to_db(power) - reference))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn snapshot_of(signal: impl Fn(f64) -> f64, rate: f64) -> TanpuraSnapshot {
        let mut snapshot = TanpuraSnapshot {
            sample_rate_hz: rate,
            force_len: FORCE_HISTORY_SAMPLES,
            ..TanpuraSnapshot::default()
        };
        for (i, force) in snapshot.force_n.iter_mut().enumerate() {
            *force = signal(i as f64 / rate) as f32;
        }
        snapshot
    }

    #[test]
    fn a_sine_peaks_in_its_bin_and_a_band_has_its_centroid() {
        let rate = 44_100.0;
        let mut analysis = ForceAnalysis::default();
        let frequency = 40.0 * rate / FORCE_HISTORY_SAMPLES as f64; // exactly bin 40
        analysis.update(&snapshot_of(
            |t| 0.3 * (2.0 * std::f64::consts::PI * frequency * t).sin(),
            rate,
        ));
        let peak = analysis
            .spectrum_db()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        assert_eq!(peak.0, frequency);
        assert!(peak.1.abs() < 1e-9, "the peak is the reference level");
        assert_eq!(analysis.spectrogram_db.len(), 1);

        // Two equal partials at 2 and 4 kHz (bin centres): centroid 3 kHz.
        let bin = rate / FORCE_HISTORY_SAMPLES as f64;
        let (low, high) = ((2000.0 / bin).round() * bin, (4000.0 / bin).round() * bin);
        analysis.update(&snapshot_of(
            |t| {
                (2.0 * std::f64::consts::PI * low * t).sin()
                    + (2.0 * std::f64::consts::PI * high * t).sin()
            },
            rate,
        ));
        let centroid = *analysis.centroid_hz.last().unwrap();
        assert!(
            (centroid - (low + high) / 2.0).abs() < 1.0,
            "centroid {centroid} Hz"
        );
    }

    #[test]
    fn the_spectrogram_keeps_the_last_frames() {
        let mut analysis = ForceAnalysis::default();
        let silent = snapshot_of(|_| 0.0, 48_000.0);
        for _ in 0..SPECTROGRAM_FRAMES + 7 {
            analysis.update(&silent);
        }
        assert_eq!(analysis.spectrogram_db.len(), SPECTROGRAM_FRAMES);
        assert_eq!(analysis.centroid_hz.len(), SPECTROGRAM_FRAMES);
        assert!(analysis.centroid_hz.iter().all(|c| c.is_nan()));
        // A short history (the first frames after opening) is not analysed.
        let mut short = silent;
        short.force_len = 100;
        let before = analysis.spectrogram_db.len();
        analysis.changed = false;
        analysis.update(&short);
        assert_eq!(analysis.spectrogram_db.len(), before);
        assert!(!analysis.changed);
    }
}
