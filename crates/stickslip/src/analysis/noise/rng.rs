//! Random numbers for the ensembles: xoshiro256++ (Blackman & Vigna, "Scrambled linear
//! pseudorandom number generators", ACM TOMS 47, 2021) seeded through SplitMix64, one stream per
//! realisation, and standard normal deviates by the Box–Muller transform.
//!
//! Realisation `index` of a run with seed `seed` uses the stream whose 256-bit state is four
//! SplitMix64 outputs from the key mix(mix(seed) ⊕ index) (mix = SplitMix64's output function,
//! a bijection of u64): distinct indices get distinct states, and a realisation's numbers depend
//! on (seed, index) only, never on the thread that computes it or on the other realisations.
//! That makes an ensemble bit-for-bit reproducible whatever the number of threads.

/// SplitMix64 (Steele, Lea & Flood 2014; Vigna's reference splitmix64.c).
#[derive(Debug, Clone)]
pub struct SplitMix64 {
    state: u64,
}

/// SplitMix64's output function: a bijective 64-bit mixer.
pub fn mix64(z: u64) -> u64 {
    let z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    let z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl SplitMix64 {
    /// The generator with the given state.
    pub fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        mix64(self.state)
    }
}

/// xoshiro256++ with a Box–Muller normal sampler (the second deviate of each pair is kept for
/// the next call).
#[derive(Debug, Clone)]
pub struct Rng {
    s: [u64; 4],
    spare: Option<f64>,
}

impl Rng {
    /// A generator with the raw state `s` (not all zero).
    pub fn from_state(s: [u64; 4]) -> Self {
        Self { s, spare: None }
    }

    /// The stream of realisation `index` of a run seeded with `seed` (see the module docs).
    pub fn for_realisation(seed: u64, index: u64) -> Self {
        let mut sm = SplitMix64::new(mix64(mix64(seed) ^ index));
        let s = [sm.next_u64(), sm.next_u64(), sm.next_u64(), sm.next_u64()];
        // SplitMix64 never yields four zeros in a row from one state (its outputs are a
        // bijection of four distinct counters), so the xoshiro state is valid.
        Self::from_state(s)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        let s = &mut self.s;
        let result = s[0].wrapping_add(s[3]).rotate_left(23).wrapping_add(s[0]);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        result
    }

    /// A uniform deviate in (0, 1]: the top 53 bits, shifted away from 0.
    pub fn uniform_open0(&mut self) -> f64 {
        ((self.next_u64() >> 11) + 1) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// A standard normal deviate (Box–Muller: √(−2 ln u1)·(cos, sin)(2π u2)).
    pub fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        let (u1, u2) = (self.uniform_open0(), self.uniform_open0());
        let radius = (-2.0 * u1.ln()).sqrt();
        let (sin, cos) = (std::f64::consts::TAU * u2).sin_cos();
        self.spare = Some(radius * sin);
        radius * cos
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix64_matches_the_published_vectors() {
        // Vigna's splitmix64.c from state 0.
        let mut g = SplitMix64::new(0);
        assert_eq!(g.next_u64(), 0xe220_a839_7b1d_cdaf);
        assert_eq!(g.next_u64(), 0x6e78_9e6a_a1b9_65f4);
        assert_eq!(g.next_u64(), 0x06c4_5d18_8009_454f);
    }

    #[test]
    fn xoshiro256plusplus_matches_the_reference_implementation() {
        // xoshiro256plusplus.c from the state {1, 2, 3, 4} (the vector rand_xoshiro checks).
        let mut g = Rng::from_state([1, 2, 3, 4]);
        let expected: [u64; 10] = [
            41943041,
            58720359,
            3588806011781223,
            3591011842654386,
            9228616714210784205,
            9973669472204895162,
            14011001112246962877,
            12406186145184390807,
            15849039046786891736,
            10450023813501588000,
        ];
        for e in expected {
            assert_eq!(g.next_u64(), e);
        }
    }

    #[test]
    fn normal_deviates_have_unit_moments() {
        // 4e5 deviates: the sample mean has standard error 1.6e-3, the variance 2.2e-3, the
        // fourth moment (3) 1.6e-2; bounds at about 5 standard errors.
        let mut g = Rng::for_realisation(7, 3);
        let n = 400_000;
        let (mut s1, mut s2, mut s4) = (0.0, 0.0, 0.0);
        for _ in 0..n {
            let z = g.normal();
            s1 += z;
            s2 += z * z;
            s4 += z * z * z * z;
        }
        let n = n as f64;
        assert!((s1 / n).abs() < 8e-3, "mean {}", s1 / n);
        assert!((s2 / n - 1.0).abs() < 1.1e-2, "variance {}", s2 / n);
        assert!((s4 / n - 3.0).abs() < 8e-2, "fourth moment {}", s4 / n);
    }

    #[test]
    fn streams_depend_on_seed_and_index_only() {
        let a: Vec<u64> = (0..4)
            .map(|_| 0)
            .scan(Rng::for_realisation(1, 5), |g, _: u64| Some(g.next_u64()))
            .collect();
        let b: Vec<u64> = (0..4)
            .map(|_| 0)
            .scan(Rng::for_realisation(1, 5), |g, _: u64| Some(g.next_u64()))
            .collect();
        let c: Vec<u64> = (0..4)
            .map(|_| 0)
            .scan(Rng::for_realisation(1, 6), |g, _: u64| Some(g.next_u64()))
            .collect();
        let d: Vec<u64> = (0..4)
            .map(|_| 0)
            .scan(Rng::for_realisation(2, 5), |g, _: u64| Some(g.next_u64()))
            .collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
        assert_ne!(a, d);
    }
}
