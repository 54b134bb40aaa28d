//! WAV files of rendered audio: mono, 32-bit float, full scale ±1 (hound).

use std::path::Path;

/// Writes a mono 32-bit float WAV file, creating its directory. The error names the file.
pub fn write_wav(path: &Path, signal: &[f32], sample_rate_hz: f64) -> Result<(), String> {
    if let Some(parent) = path
        .parent()
        .filter(|parent| !parent.as_os_str().is_empty())
    {
        std::fs::create_dir_all(parent)
            .map_err(|error| format!("cannot create {}: {error}", parent.display()))?;
    }
    let spec = hound::WavSpec {
        channels: 1,
        sample_rate: sample_rate_hz.round() as u32,
        bits_per_sample: 32,
        sample_format: hound::SampleFormat::Float,
    };
    let fail = |error: hound::Error| format!("cannot write {}: {error}", path.display());
    let mut writer = hound::WavWriter::create(path, spec).map_err(fail)?;
    for sample in signal {
        writer.write_sample(*sample).map_err(fail)?;
    }
    writer.finalize().map_err(fail)
}

/// Reads a mono 32-bit float WAV file written by [`write_wav`] (or a stereo one, as its mid
/// signal `(left + right) / 2`, which is the mono output for Javari's stereo): the samples and
/// the rate, Hz.
pub fn read_wav(path: &Path) -> Result<(Vec<f32>, f64), String> {
    let fail = |error: hound::Error| format!("cannot read {}: {error}", path.display());
    let mut reader = hound::WavReader::open(path).map_err(fail)?;
    let spec = reader.spec();
    if !(spec.channels == 1 || spec.channels == 2)
        || spec.sample_format != hound::SampleFormat::Float
    {
        return Err(format!(
            "{}: expected mono or stereo 32-bit float, found {} channels of {:?}",
            path.display(),
            spec.channels,
            spec.sample_format
        ));
    }
    let samples = reader
        .samples::<f32>()
        .collect::<Result<Vec<f32>, _>>()
        .map_err(fail)?;
    let samples = if spec.channels == 2 {
        samples
            .chunks_exact(2)
            .map(|pair| 0.5 * (pair[0] + pair[1]))
            .collect()
    } else {
        samples
    };
    Ok((samples, f64::from(spec.sample_rate)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_is_bit_exact() {
        let path = std::env::temp_dir().join(format!("javari-wav-{}.wav", std::process::id()));
        let signal = [0.0f32, 0.5, -1.0, 1e-30, 0.123_456_79];
        write_wav(&path, &signal, 48_000.0).unwrap();
        let (read, rate) = read_wav(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(read, signal);
        assert_eq!(rate, 48_000.0);
    }
}
