//! The exact floating-point summation orders of docs/spec/aitm.md §2 and §4.
//!
//! With 3-decimal inputs, mathematically equal distances are common, and the
//! last bit of a computed distance decides winners and threshold tests. The
//! order of the additions is therefore part of the specification.

/// Ranking distance `|a − b|` of docs/spec/aitm.md §2: the square root of the squared
/// component differences summed in the blocked ("pairwise") order.
#[inline]
pub(crate) fn ranking_distance(a: &[f64], b: &[f64]) -> f64 {
    pairwise_sq_sum(a, b).sqrt()
}

/// Sum of `(a_j − b_j)²` in the order of docs/spec/aitm.md §2: left to right below 8
/// components; for 8 to 128 components eight interleaved partial sums
/// combined as a balanced tree, then the `n mod 8` remaining terms in index
/// order. Above 128 components (not used by any instance) the slice is split
/// as the array library did (first half rounded down to a multiple of 8) and
/// both halves are summed recursively.
#[inline]
pub(crate) fn pairwise_sq_sum(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    if n < 8 {
        let mut sum = 0.0;
        for (x, y) in a.iter().zip(b) {
            let d = x - y;
            sum += d * d;
        }
        sum
    } else if n <= 128 {
        let full = n - n % 8;
        let mut r = [0.0_f64; 8];
        for (k, rk) in r.iter_mut().enumerate() {
            let d = a[k] - b[k];
            *rk = d * d;
        }
        for (ca, cb) in a[8..full].chunks_exact(8).zip(b[8..full].chunks_exact(8)) {
            for k in 0..8 {
                let d = ca[k] - cb[k];
                r[k] += d * d;
            }
        }
        let mut sum = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
        for (x, y) in a[full..].iter().zip(&b[full..]) {
            let d = x - y;
            sum += d * d;
        }
        sum
    } else {
        let half = n / 2;
        let half = half - half % 8;
        pairwise_sq_sum(&a[..half], &b[..half]) + pairwise_sq_sum(&a[half..], &b[half..])
    }
}

/// Threshold norm `|a − b|` of docs/spec/aitm.md §4: square root of the left-to-right
/// sum of squares.
#[inline]
pub(crate) fn lr_distance(a: &[f64], b: &[f64]) -> f64 {
    lr_sq_distance(a, b).sqrt()
}

/// Left-to-right `Σ (a_j − b_j)²`.
#[inline]
pub(crate) fn lr_sq_distance(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    let mut sum = 0.0;
    for (x, y) in a.iter().zip(b) {
        let d = x - y;
        sum += d * d;
    }
    sum
}

/// Left-to-right `Σ a_j²`.
#[inline]
pub(crate) fn lr_sq_norm(a: &[f64]) -> f64 {
    let mut sum = 0.0;
    for x in a {
        sum += x * x;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference: the blocked order written out literally for 8 and 10
    /// components (docs/spec/aitm.md §2).
    fn literal(e: &[f64]) -> f64 {
        let b8 = ((e[0] + e[1]) + (e[2] + e[3])) + ((e[4] + e[5]) + (e[6] + e[7]));
        match e.len() {
            8 => b8,
            10 => b8 + e[8] + e[9],
            _ => unreachable!("only 8 and 10 are written out"),
        }
    }

    fn squares(a: &[f64]) -> Vec<f64> {
        a.iter().map(|x| x * x).collect()
    }

    #[test]
    fn small_vectors_sum_left_to_right() {
        // 0.1² + 0.2² + 0.3²: left to right differs from (0.3² + 0.2²) + 0.1².
        let a = [0.1, 0.2, 0.3];
        let zero = [0.0; 3];
        let e = squares(&a);
        assert_eq!(pairwise_sq_sum(&a, &zero), (e[0] + e[1]) + e[2]);
        assert_eq!(pairwise_sq_sum(&[], &[]), 0.0);
    }

    #[test]
    fn eight_and_ten_components_use_blocked_tree() {
        let mut state = 0x1234_5678_9abc_def0_u64;
        let mut differs = 0;
        for _ in 0..2000 {
            for n in [8usize, 10] {
                let a: Vec<f64> = (0..n)
                    .map(|_| {
                        state ^= state << 13;
                        state ^= state >> 7;
                        state ^= state << 17;
                        ((state % 2001) as f64 - 1000.0) / 1000.0
                    })
                    .collect();
                let zero = vec![0.0; n];
                let e = squares(&a);
                let blocked = pairwise_sq_sum(&a, &zero);
                assert_eq!(blocked.to_bits(), literal(&e).to_bits());
                if blocked != lr_sq_distance(&a, &zero) {
                    differs += 1;
                }
            }
        }
        // docs/spec/aitm.md §2: the two orders differ for a large share of inputs, so
        // this check is not vacuous.
        assert!(differs > 100, "{differs}");
    }

    #[test]
    fn remainder_after_blocks_is_added_in_index_order() {
        // 19 components: blocks 0..8 and 8..16, remainder 16, 17, 18.
        let a: Vec<f64> = (0..19).map(|j| 0.013 * j as f64 + 0.001).collect();
        let zero = vec![0.0; 19];
        let e = squares(&a);
        let mut r = [0.0; 8];
        for k in 0..8 {
            r[k] = e[k] + e[k + 8];
        }
        let expected =
            ((((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))) + e[16] + e[17])
                + e[18];
        assert_eq!(pairwise_sq_sum(&a, &zero).to_bits(), expected.to_bits());
    }

    #[test]
    fn long_vectors_split_recursively() {
        // 200 components: 100 → rounded to 96, then sums over 96 and 104.
        let a: Vec<f64> = (0..200).map(|j| 1.0 / (j as f64 + 1.0)).collect();
        let zero = vec![0.0; 200];
        let expected =
            pairwise_sq_sum(&a[..96], &zero[..96]) + pairwise_sq_sum(&a[96..], &zero[96..]);
        assert_eq!(pairwise_sq_sum(&a, &zero).to_bits(), expected.to_bits());
    }

    #[test]
    fn threshold_norms_are_left_to_right() {
        let a = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8];
        let mut s = 0.0;
        for x in a {
            s += x * x;
        }
        assert_eq!(lr_sq_norm(&a), s);
        assert_eq!(lr_distance(&a, &[0.0; 8]), s.sqrt());
    }
}
