//! Values read off the front of a fuzzer's input, for the targets that build structured
//! inputs (the estimator's readings, SLAM's scans): zeros once the bytes end.

pub struct Bytes<'a>(pub &'a [u8]);

impl Bytes<'_> {
    pub fn u8(&mut self) -> u8 {
        let (v, rest) = self.0.split_first().map_or((0, &[][..]), |(v, r)| (*v, r));
        self.0 = rest;
        v
    }

    pub fn u16(&mut self) -> u16 {
        u16::from(self.u8()) | u16::from(self.u8()) << 8
    }

    /// Any f64 bit pattern (NaN, ±inf, 10³⁰⁸, subnormals).
    pub fn any_f64(&mut self) -> f64 {
        f64::from_bits((0..8).fold(0u64, |a, i| a | u64::from(self.u8()) << (8 * i)))
    }

    /// A small plausible value, `(u16 − 32768) / scale`.
    pub fn small(&mut self, scale: f64) -> f64 {
        (f64::from(self.u16()) - 32768.0) / scale
    }
}
