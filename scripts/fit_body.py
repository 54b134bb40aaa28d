#!/usr/bin/env python3
"""Fits the tanpura body's resonances (core/src/tanpura/body.rs, TANPURA_BODY) to a measured
bridge-force-to-sound-pressure impulse response.

Data: van Walstijn, Bridges & Mehes, "A real-time synthesis oriented tanpura model", DAFx-16,
section 3.3 and Fig. 5: impact hammer at the bridge, microphone 80 cm from the instrument, 2048
samples at 44.1 kHz, published on the paper's companion page as `hb.wav` (the research page of
S. Mehes, publications/dafx16/audio/radiation filtering/hb.wav). The file is not part of this
repository; fetch it and run

    python3 -m venv /tmp/venv && /tmp/venv/bin/pip install numpy scipy
    /tmp/venv/bin/python scripts/fit_body.py path/to/hb.wav

Method (the parallel second-order form the paper suggests, after Bank, ICMC 2007, restricted to
band-pass sections so that each one is a passive oscillator):
1. the measured magnitude response, smoothed over 1/12 octave;
2. resonances at its peaks from 60 Hz to 16 kHz (at least 1/12 octave apart), each with the Q of
   its half-power bandwidth (clamped to 2..60);
3. gains by non-negative least squares on the power spectrum, |H|^2 ~ sum_k G_k^2 |H_k|^2, on a
   logarithmic frequency grid (the cross terms of neighbouring resonances are neglected);
4. the gains scaled so that the body's power gain, averaged over 100 Hz - 10 kHz on the same
   logarithmic grid, is 1: the radiated output is then as loud as the bridge force it comes from.
Prints the Rust table and the fit's RMS error in dB over 60 Hz - 16 kHz.
"""
import sys
import wave

import numpy as np
from scipy.optimize import nnls

RATE = 44_100.0


def read_wav(path):
    with wave.open(path, "rb") as w:
        assert w.getsampwidth() == 2 and w.getnchannels() == 1
        rate = w.getframerate()
        data = np.frombuffer(w.readframes(w.getnframes()), dtype="<i2").astype(float)
    return data / 32768.0, rate


def band_pass_power(f, fk, q):
    # |G 2 sigma s / (s^2 + 2 sigma s + w^2)|^2 at s = j 2 pi f, with G = 1.
    w, wk = 2 * np.pi * f, 2 * np.pi * fk
    sigma = 0.5 * wk / q
    num = (2 * sigma * w) ** 2
    den = (wk**2 - w**2) ** 2 + (2 * sigma * w) ** 2
    return num / den


def main(path):
    h, rate = read_wav(path)
    assert rate == RATE, rate
    n = 1 << 16
    spectrum = np.abs(np.fft.rfft(h, n))
    freqs = np.fft.rfftfreq(n, 1 / rate)
    # 1/12-octave smoothing of the power.
    power = spectrum**2
    smooth = np.empty_like(power)
    for i, f in enumerate(freqs):
        lo, hi = f * 2 ** (-1 / 24), f * 2 ** (1 / 24)
        a, b = np.searchsorted(freqs, [lo, hi])
        smooth[i] = power[a : max(b, a + 1)].mean()
    grid = np.geomspace(60, 16_000, 600)
    target = np.interp(grid, freqs, smooth)
    # Peaks of the smoothed response on the grid.
    peaks = [i for i in range(1, len(grid) - 1) if target[i] > target[i - 1] and target[i] >= target[i + 1]]
    resonances = []
    for i in peaks:
        fk = grid[i]
        half = target[i] / 2
        lo = i
        while lo > 0 and target[lo] > half:
            lo -= 1
        hi = i
        while hi < len(grid) - 1 and target[hi] > half:
            hi += 1
        bandwidth = max(grid[hi] - grid[lo], 1e-9)
        q = float(np.clip(fk / bandwidth, 2.0, 60.0))
        resonances.append((fk, q))
    basis = np.array([band_pass_power(grid, fk, q) for fk, q in resonances]).T
    weights, _ = nnls(basis, target)
    kept = [(fk, q, np.sqrt(w)) for (fk, q), w in zip(resonances, weights) if w > 0]
    model = sum(g**2 * band_pass_power(grid, fk, q) for fk, q, g in kept)
    band = (grid >= 100) & (grid <= 10_000)
    scale = 1 / np.sqrt(model[band].mean())
    kept = [(fk, q, g * scale) for fk, q, g in kept]
    model *= scale**2
    target_scaled = target * scale**2
    error_db = 10 * np.log10(model / target_scaled)
    print(f"// {len(kept)} resonances; fit RMS error {np.sqrt(np.mean(error_db**2)):.2f} dB over 60 Hz - 16 kHz")
    print(f"pub const TANPURA_BODY: [BodyResonance; {len(kept)}] = [")
    for fk, q, g in kept:
        print(f"    BodyResonance {{ frequency_hz: {fk:.1f}, quality: {q:.2f}, gain: {g:.4f} }},")
    print("];")


if __name__ == "__main__":
    main(sys.argv[1])
