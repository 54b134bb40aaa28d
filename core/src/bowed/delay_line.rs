//! The history of a travelling wave, read at fixed and fractional delays: the delay line both
//! bowed tiers are built on.
//!
//! Cheap by construction, because it runs once or twice per sample per line:
//!
//! - the length is a power of two, so the write position wraps with a mask;
//! - every value is stored twice, at `write` and at `write + size`, so any stretch of up to
//!   `size` past values is one contiguous slice of the buffer: a convolution window or the two
//!   neighbours of a fractional read are taken with one range check, without a wrap-around test
//!   per tap;
//! - a fractional delay is split into whole samples and a fraction once, when the delay changes
//!   ([`FractionalDelay`]), not per sample (on generic x86-64 `f64::floor` is a library call and
//!   the float-to-integer conversion saturates, together about 40 instructions).

/// A delay in samples, split once into its whole part and its fraction for linear interpolation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FractionalDelay {
    whole: usize,
    fraction: f64,
    samples: f64,
}

impl FractionalDelay {
    /// `delay_samples` clamped to [1, `max_samples`] (a non-finite delay is taken as 1), so
    /// that both neighbours of the read lie in the past and inside the history.
    pub fn new(delay_samples: f64, max_samples: f64) -> Self {
        let samples = if delay_samples.is_finite() {
            delay_samples.clamp(1.0, max_samples.max(1.0))
        } else {
            1.0
        };
        let whole = samples.floor();
        Self {
            whole: whole as usize,
            fraction: samples - whole,
            samples,
        }
    }

    /// The delay after clamping, samples.
    pub fn samples(&self) -> f64 {
        self.samples
    }

    /// The whole samples of the delay: a read at this delay sees no value pushed in the last
    /// `whole() − 1` samples.
    #[inline]
    pub fn whole(&self) -> usize {
        self.whole
    }

    /// The fraction of a sample beyond [`Self::whole`], interpolated linearly.
    #[inline]
    pub fn fraction(&self) -> f64 {
        self.fraction
    }
}

/// A power-of-two ring of past values, mirrored so that windows never wrap.
#[derive(Clone, Debug)]
pub struct DelayHistory {
    /// 2 · `size` values; `buffer[i]` and `buffer[i + size]` always hold the same value.
    buffer: Vec<f64>,
    size: usize,
    /// Where the next value goes, 0 ≤ write < size.
    write: usize,
}

impl DelayHistory {
    /// Room for at least `min_size` past values (rounded up to a power of two).
    pub fn new(min_size: usize) -> Self {
        let size = min_size.max(2).next_power_of_two();
        Self {
            buffer: vec![0.0; 2 * size],
            size,
            write: 0,
        }
    }

    /// How many past values the history holds (a power of two).
    pub fn size(&self) -> usize {
        self.size
    }

    /// Store this sample's value.
    #[inline]
    pub fn push(&mut self, value: f64) {
        self.cursor().push(value);
    }

    /// The `count` values pushed `newest_delay + count − 1` down to `newest_delay` samples ago,
    /// oldest first (`newest_delay` ≥ 1 is the value pushed last; `newest_delay + count − 1`
    /// ≤ size). Outside that range: an empty slice, never a panic.
    #[inline]
    pub fn window(&self, newest_delay: usize, count: usize) -> &[f64] {
        window(&self.buffer, self.size, self.write, newest_delay, count)
    }

    /// The value of `delay` ago, linearly interpolated between its two neighbours.
    #[inline]
    pub fn read(&self, delay: &FractionalDelay) -> f64 {
        read(&self.buffer, self.size, self.write, delay)
    }

    /// The history for a run of samples, with its write position in a local variable (a
    /// register) instead of in the struct: a block loop then carries no store-to-load
    /// dependency from one sample's push to the next sample's reads. The position is written
    /// back when the cursor is dropped.
    #[inline]
    pub fn cursor(&mut self) -> DelayCursor<'_> {
        DelayCursor {
            buffer: &mut self.buffer,
            size: self.size,
            write: self.write,
            home: &mut self.write,
        }
    }

    /// Zero every value.
    pub fn reset(&mut self) {
        self.buffer.fill(0.0);
        self.write = 0;
    }
}

/// A [`DelayHistory`] borrowed for a run of samples (see [`DelayHistory::cursor`]).
#[derive(Debug)]
pub struct DelayCursor<'a> {
    buffer: &'a mut [f64],
    size: usize,
    write: usize,
    home: &'a mut usize,
}

impl DelayCursor<'_> {
    /// Store this sample's value.
    #[inline]
    pub fn push(&mut self, value: f64) {
        // write < size: both slots exist; `get_mut` keeps a broken invariant from panicking.
        if let Some(high) = self.buffer.get_mut(self.write + self.size) {
            *high = value;
        }
        if let Some(low) = self.buffer.get_mut(self.write) {
            *low = value;
        }
        self.write = (self.write + 1) & (self.size - 1);
    }

    /// As [`DelayHistory::window`].
    /// Reads `into.len()` consecutive samples at `delay`, as that many [`Self::read`] calls
    /// between pushes would, for a run whose values are pushed after it
    /// ([`Self::push_run`]); false (nothing read) when the delay's whole samples are fewer than
    /// the run, so that a read would need a value of the run itself.
    #[inline(always)]
    pub fn read_run(&self, delay: &FractionalDelay, into: &mut [f64]) -> bool {
        let count = into.len();
        if count == 0 || delay.whole < count {
            return false;
        }
        // Sample k reads the pair k samples after the first's.
        let pairs = self.window(delay.whole + 1 - count, count + 1);
        if pairs.len() != count + 1 {
            return false;
        }
        for (value, pair) in into.iter_mut().zip(pairs.windows(2)) {
            let (older, newer) = (pair[0], pair[1]);
            *value = newer + delay.fraction * (older - newer);
        }
        true
    }

    /// Pushes `values` in order, as that many [`Self::push`] calls would.
    #[inline]
    pub fn push_run(&mut self, values: &[f64]) {
        let mut rest = values;
        while !rest.is_empty() {
            // Up to the end of the ring, then from its start.
            let length = rest.len().min(self.size - self.write);
            let (now, later) = rest.split_at(length);
            let low = self.write..self.write + length;
            let high = self.write + self.size..self.write + self.size + length;
            // Element by element: runs are a few samples, shorter than a `memmove` call.
            if let Some(slice) = self.buffer.get_mut(low) {
                for (stored, &value) in slice.iter_mut().zip(now) {
                    *stored = value;
                }
            }
            if let Some(slice) = self.buffer.get_mut(high) {
                for (stored, &value) in slice.iter_mut().zip(now) {
                    *stored = value;
                }
            }
            self.write = (self.write + length) & (self.size - 1);
            rest = later;
        }
    }

    #[inline]
    pub fn window(&self, newest_delay: usize, count: usize) -> &[f64] {
        window(self.buffer, self.size, self.write, newest_delay, count)
    }

    /// As [`DelayHistory::read`].
    #[inline]
    pub fn read(&self, delay: &FractionalDelay) -> f64 {
        read(self.buffer, self.size, self.write, delay)
    }

    /// Zero every value (the voice's reset after a non-finite sample).
    pub fn reset(&mut self) {
        self.buffer.fill(0.0);
        self.write = 0;
    }
}

impl Drop for DelayCursor<'_> {
    fn drop(&mut self) {
        *self.home = self.write;
    }
}

#[inline]
fn window(buffer: &[f64], size: usize, write: usize, newest_delay: usize, count: usize) -> &[f64] {
    if newest_delay == 0 || newest_delay.saturating_add(count) > size + 1 {
        return &[];
    }
    // write + size − d is the mirrored position of the value pushed d samples ago.
    let newest = (write + size).wrapping_sub(newest_delay);
    let oldest = (newest + 1).wrapping_sub(count);
    buffer.get(oldest..=newest).unwrap_or(&[])
}

#[inline]
fn read(buffer: &[f64], size: usize, write: usize, delay: &FractionalDelay) -> f64 {
    // The mirrored positions of the values pushed `whole` and `whole + 1` samples ago.
    let newer = (write + size).wrapping_sub(delay.whole);
    match (buffer.get(newer.wrapping_sub(1)), buffer.get(newer)) {
        (Some(&older), Some(&newer)) => newer + delay.fraction * (older - newer),
        _ => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_and_reads_see_the_past_across_the_wrap() {
        let mut history = DelayHistory::new(8);
        assert_eq!(history.size(), 8);
        for n in 0..21 {
            history.push(n as f64);
        }
        // Last pushed 20 is 1 sample ago; a window of 3 ending 2 samples ago is [17, 18, 19].
        assert_eq!(history.window(1, 1), &[20.0]);
        assert_eq!(history.window(2, 3), &[17.0, 18.0, 19.0]);
        assert_eq!(
            history.window(1, 8),
            &[13.0, 14.0, 15.0, 16.0, 17.0, 18.0, 19.0, 20.0]
        );
        // Beyond the history: empty, not a panic.
        assert!(history.window(2, 8).is_empty());
        let delay = FractionalDelay::new(2.5, 6.0);
        assert!((history.read(&delay) - 18.5).abs() < 1e-15);
        // Clamped to [1, max].
        assert_eq!(FractionalDelay::new(0.2, 6.0).samples(), 1.0);
        assert_eq!(FractionalDelay::new(9.0, 6.0).samples(), 6.0);
        assert_eq!(FractionalDelay::new(f64::NAN, 6.0).samples(), 1.0);
    }
}
