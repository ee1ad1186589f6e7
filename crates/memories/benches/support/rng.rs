//! SplitMix64: deterministic bench inputs without an extra dependency. One
//! file, included with `#[path]` by the AITM benchmarks.

pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A 3-decimal value in [−half, half] thousandths.
    pub fn grid(&mut self, half: i64) -> f64 {
        let k = (self.next() % (2 * half as u64 + 1)) as i64 - half;
        k as f64 / 1000.0
    }

    #[allow(dead_code)] // used by one of the including benches only
    pub fn vec(&mut self, dim: usize, half: i64) -> Vec<f64> {
        (0..dim).map(|_| self.grid(half)).collect()
    }
}
