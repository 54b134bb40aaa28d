"""Renders the bundled Javari VST3 with pedalboard (a real VST3 host library from PyPI) from a
MIDI note list and checks what a listener would: the plugin loads as an instrument, the output is
finite, below full scale, silent before the first note, and each note sounds at its pitch.

Usage: python render_vst3.py target/bundled/javari.vst3
Exits non-zero with a message on the first failed check; prints a closing
"N passed, N failed" line.
"""

import sys

import numpy as np
from pedalboard import load_plugin

SAMPLE_RATE = 44100.0
# (MIDI key, start s): each note is silenced (CC 120) 0.55 s later, before the next one.
NOTES = [(45, 0.1), (57, 0.8), (64, 1.5), (69, 2.2)]
VELOCITY = 48
DURATION_S = 2.9


def note_hz(key):
    return 440.0 * 2.0 ** ((key - 69) / 12.0)


def peak_frequency_near(signal, expected_hz, search_cents=60.0):
    """Strongest Hann-windowed DTFT peak within +-search_cents of expected_hz (0.05 cent grid)."""
    window = np.hanning(len(signal))
    n = np.arange(len(signal))
    cents = np.arange(-search_cents, search_cents, 0.05)
    best = (None, -1.0)
    weighted = signal * window
    for chunk in np.array_split(cents, 24):
        freqs = expected_hz * 2.0 ** (chunk / 1200.0)
        phasors = np.exp(-2j * np.pi * np.outer(freqs, n) / SAMPLE_RATE)
        magnitudes = np.abs(phasors @ weighted)
        index = int(np.argmax(magnitudes))
        if magnitudes[index] > best[1]:
            best = (freqs[index], magnitudes[index])
    return best[0]


def main():
    path = sys.argv[1]
    plugin = load_plugin(path)
    checks = []

    def check(name, ok, detail):
        checks.append(ok)
        print(f"{'ok  ' if ok else 'FAIL'} {name}: {detail}")

    check("loads as an instrument", plugin.is_instrument, f"{plugin.name}")
    messages = []
    for key, start in NOTES:
        messages.append(([0x90, key, VELOCITY], start))
        messages.append(([0x80, key, 0], start + 0.3))
        messages.append(([0xB0, 120, 0], start + 0.55))
    audio = plugin(messages, duration=DURATION_S, sample_rate=SAMPLE_RATE, num_channels=2,
                   buffer_size=512)
    left = audio[0].astype(np.float64)
    check("length", audio.shape == (2, int(DURATION_S * SAMPLE_RATE)), f"{audio.shape}")
    check("finite", bool(np.all(np.isfinite(audio))), "no NaN or Inf")
    peak = float(np.max(np.abs(audio)))
    check("below full scale", 1e-3 < peak < 1.0, f"peak {20 * np.log10(peak):.2f} dBFS")
    first = int(NOTES[0][1] * SAMPLE_RATE)
    check("silent before the first note", float(np.max(np.abs(left[:first]))) == 0.0, "")
    for key, start in NOTES:
        begin = int((start + 0.1) * SAMPLE_RATE)
        end = int((start + 0.5) * SAMPLE_RATE)
        expected = note_hz(key)
        measured = peak_frequency_near(left[begin:end], expected)
        cents = 1200.0 * np.log2(measured / expected)
        check(f"pitch of note {key}", abs(cents) < 5.0,
              f"expected {expected:.3f} Hz, measured {measured:.3f} Hz ({cents:+.2f} cents)")
    passed = sum(checks)
    failed = len(checks) - passed
    print(f"pedalboard: {passed} passed, {failed} failed")
    return 0 if failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
