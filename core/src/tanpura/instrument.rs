//! The four-string drone instrument: first string (Pa, Ma, Ni, komal Ni or Dha), Sa, Sa, low Sa, each a
//! [`TanpuraVoice`].

use super::excitation::Pluck;
use super::voice::{TanpuraVoice, VoiceSettings};
use crate::newton::NewtonStats;

/// The interval of the first drone string below Sa.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FirstString {
    /// The fifth: 3/4 of Sa (Pa of the lower octave).
    Pa,
    /// The fourth: 2/3 of Sa (Ma of the lower octave).
    Ma,
    /// The major seventh, shuddha Ni: 15/16 of Sa (15/8 an octave lower).
    Ni,
    /// The minor seventh, komal Ni: 8/9 of Sa (16/9, two just fourths, an octave lower).
    KomalNi,
    /// The major sixth, Dha: 5/6 of Sa (5/3 an octave lower).
    Dha,
}

impl FirstString {
    /// Every first string, in the order the plugin and presets list them.
    pub const ALL: [FirstString; 5] = [
        FirstString::Pa,
        FirstString::Ma,
        FirstString::Ni,
        FirstString::KomalNi,
        FirstString::Dha,
    ];

    /// Frequency ratio to Sa: just intonation, the lower octave.
    pub fn ratio(self) -> f64 {
        match self {
            FirstString::Pa => 3.0 / 4.0,
            FirstString::Ma => 2.0 / 3.0,
            FirstString::Ni => 15.0 / 16.0,
            FirstString::KomalNi => 8.0 / 9.0,
            FirstString::Dha => 5.0 / 6.0,
        }
    }
}

/// The four-string drone: first string (Pa, Ma or Ni), Sa, Sa, low Sa.
#[derive(Debug, Clone)]
pub struct Tanpura {
    voices: [TanpuraVoice; 4],
    settings: VoiceSettings,
    sa_hz: f64,
    first_string: FirstString,
}

impl Tanpura {
    /// Frequency ratios of the four strings to Sa for a given first string.
    pub fn tuning(first_string: FirstString) -> [f64; 4] {
        [first_string.ratio(), 1.0, 1.0, 0.5]
    }

    /// The instrument tuned to `sa_hz`; `settings` apply to every string except its pitch.
    /// Allocates.
    pub fn new(settings: &VoiceSettings, sa_hz: f64, output_sample_rate_hz: f64) -> Self {
        let ratios = Self::tuning(FirstString::Pa);
        let voices = ratios.map(|ratio| {
            let mut string_settings = *settings;
            string_settings.fundamental_hz = sa_hz * ratio;
            TanpuraVoice::new(&string_settings, output_sample_rate_hz)
        });
        Self {
            voices,
            settings: *settings,
            sa_hz,
            first_string: FirstString::Pa,
        }
    }

    /// Retunes and reconfigures every string without allocating.
    pub fn set_tuning(&mut self, settings: &VoiceSettings, sa_hz: f64, first_string: FirstString) {
        self.settings = *settings;
        self.sa_hz = sa_hz;
        self.first_string = first_string;
        for (voice, ratio) in self.voices.iter_mut().zip(Self::tuning(first_string)) {
            let mut string_settings = *settings;
            string_settings.fundamental_hz = sa_hz * ratio;
            voice.set_settings(&string_settings);
        }
    }

    pub fn sa_hz(&self) -> f64 {
        self.sa_hz
    }

    pub fn first_string(&self) -> FirstString {
        self.first_string
    }

    /// Plucks string `index` (0 = first string … 3 = low Sa); other indices are ignored.
    pub fn pluck(&mut self, index: usize, pluck: &Pluck) {
        if let Some(voice) = self.voices.get_mut(index) {
            voice.pluck(pluck);
        }
    }

    /// One output sample: the sum of the four strings' pickups, N. Sleeping strings cost
    /// nothing.
    pub fn next_sample(&mut self) -> f32 {
        self.voices.iter_mut().map(TanpuraVoice::next_sample).sum()
    }

    pub fn voices(&self) -> &[TanpuraVoice; 4] {
        &self.voices
    }

    /// Number of strings currently computing.
    pub fn active_strings(&self) -> usize {
        self.voices.iter().filter(|voice| voice.is_active()).count()
    }

    /// Newton statistics of all four strings together.
    pub fn newton_stats(&self) -> NewtonStats {
        let mut stats = NewtonStats::default();
        for voice in &self.voices {
            stats.merge(voice.newton_stats());
        }
        stats
    }

    pub fn reset(&mut self) {
        for voice in &mut self.voices {
            voice.reset();
        }
    }
}
