//! Frames and transforms (`docs/spec/features.md` §2).
//!
//! Every product is written out in the spec's fixed evaluation order
//! *(decision, `docs/spec/features.md` §2)*: a homogeneous product row is
//! `(M_r0·qx + M_r1·qy) + M_r2`, a 3 × 3 product entry
//! `(a_r0·b_0c + a_r1·b_1c) + a_r2·b_2c`. nalgebra's own products may sum in a
//! different order, and a last-bit difference can flip a 3-decimal rounding or
//! a threshold, so they are not used here. Rust never contracts `a·b + c` into
//! a fused multiply-add on its own, so these expressions evaluate as written.

use nalgebra::{Matrix3, Vector2};

/// `T(θ, p)`: the reference object's frame → global frame.
#[must_use]
pub fn transform(theta: f64, p: Vector2<f64>) -> Matrix3<f64> {
    let (c, s) = (theta.cos(), theta.sin());
    Matrix3::new(
        c, -s, p.x, //
        s, c, p.y, //
        0.0, 0.0, 1.0,
    )
}

/// `T⁻¹(θ, p)` built as `(Rᵀ, −Rᵀp)` with the translation entries exactly as
/// `docs/spec/features.md` §2 writes them, not by general inversion.
#[must_use]
pub fn inverse_transform(theta: f64, p: Vector2<f64>) -> Matrix3<f64> {
    let (c, s) = (theta.cos(), theta.sin());
    Matrix3::new(
        c,
        s,
        -(c * p.x + s * p.y),
        -s,
        c,
        -(-s * p.x + c * p.y),
        0.0,
        0.0,
        1.0,
    )
}

/// First two components of `M · (qx, qy, 1)`, each row as
/// `(M_r0·qx + M_r1·qy) + M_r2`.
#[must_use]
pub fn apply_homogeneous(m: &Matrix3<f64>, q: Vector2<f64>) -> Vector2<f64> {
    let row = |r: usize| (m[(r, 0)] * q.x + m[(r, 1)] * q.y) + m[(r, 2)];
    Vector2::new(row(0), row(1))
}

/// `A · B` with every entry as `(a_r0·b_0c + a_r1·b_1c) + a_r2·b_2c`.
#[must_use]
pub fn mat_mul(a: &Matrix3<f64>, b: &Matrix3<f64>) -> Matrix3<f64> {
    Matrix3::from_fn(|r, c| (a[(r, 0)] * b[(0, c)] + a[(r, 1)] * b[(1, c)]) + a[(r, 2)] * b[(2, c)])
}

/// `local_point(θ, p, q)`: `q` in the frame of an object at `p` with yaw `θ`
/// (`T⁻¹(θ, p) · (q, 1)`, unrounded).
#[must_use]
pub fn local_point(theta: f64, p: Vector2<f64>, q: Vector2<f64>) -> Vector2<f64> {
    apply_homogeneous(&inverse_transform(theta, p), q)
}

/// `global_point(θ, p, q)`: a point of the object's frame in global
/// coordinates (`T(θ, p) · (q, 1)`, unrounded).
#[must_use]
pub fn global_point(theta: f64, p: Vector2<f64>, q: Vector2<f64>) -> Vector2<f64> {
    apply_homogeneous(&transform(theta, p), q)
}

/// `local_vec(θ, v) = R(θ)ᵀ v`, unrounded; the same entries and order as the
/// rotation part of [`inverse_transform`].
#[must_use]
pub fn local_vec(theta: f64, v: Vector2<f64>) -> Vector2<f64> {
    let (c, s) = (theta.cos(), theta.sin());
    Vector2::new(c * v.x + s * v.y, -s * v.x + c * v.y)
}

/// `global_vec(θ, v) = R(θ) v`, unrounded; the same entries and order as the
/// rotation part of [`transform`].
#[must_use]
pub fn global_vec(theta: f64, v: Vector2<f64>) -> Vector2<f64> {
    let (c, s) = (theta.cos(), theta.sin());
    Vector2::new(c * v.x + -s * v.y, s * v.x + c * v.y)
}

#[cfg(test)]
mod tests {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_3};

    use proptest::prelude::*;

    use super::*;

    fn close(a: Vector2<f64>, b: Vector2<f64>) -> bool {
        (a - b).abs().max() < 1e-4
    }

    /// docs/spec/features.md §7 example 5.
    #[test]
    fn example_5_global_point_and_vector() {
        let p = Vector2::new(0.0, 0.5);
        assert!(close(
            global_point(0.0, p, Vector2::new(0.0, -0.5)),
            Vector2::new(0.0, 0.0)
        ));
        assert!(close(
            global_vec(0.0, Vector2::new(0.0, 0.5)),
            Vector2::new(0.0, 0.5)
        ));
        assert!(close(
            global_point(FRAC_PI_2, p, Vector2::new(0.0, -0.5)),
            Vector2::new(0.5, 0.5)
        ));
        assert!(close(
            global_vec(FRAC_PI_2, Vector2::new(0.0, 0.5)),
            Vector2::new(-0.5, 0.0)
        ));
    }

    /// docs/spec/features.md §7 example 6: the T⁻¹ translation column, unrounded.
    #[test]
    fn example_6_inverse_translation_column() {
        let ti = inverse_transform(FRAC_PI_3, Vector2::new(3.0, 2.0));
        let (c, s) = (FRAC_PI_3.cos(), FRAC_PI_3.sin());
        assert!((ti[(0, 2)] - -3.2321).abs() < 1e-4);
        assert!((ti[(1, 2)] - 1.5981).abs() < 1e-4);
        // Exactly the spec's expressions, bit for bit.
        assert_eq!(ti[(0, 2)], -(c * 3.0 + s * 2.0));
        assert_eq!(ti[(1, 2)], -(-s * 3.0 + c * 2.0));
        assert_eq!(ti[(2, 0)], 0.0);
        assert_eq!(ti[(2, 1)], 0.0);
        assert_eq!(ti[(2, 2)], 1.0);
    }

    #[test]
    fn transform_layout() {
        let t = transform(FRAC_PI_3, Vector2::new(3.0, 2.0));
        let (c, s) = (FRAC_PI_3.cos(), FRAC_PI_3.sin());
        assert_eq!(t, Matrix3::new(c, -s, 3.0, s, c, 2.0, 0.0, 0.0, 1.0));
        let ti = inverse_transform(FRAC_PI_3, Vector2::new(3.0, 2.0));
        assert_eq!(
            (ti[(0, 0)], ti[(0, 1)], ti[(1, 0)], ti[(1, 1)]),
            (c, s, -s, c)
        );
        let id = mat_mul(&ti, &t);
        assert!((id - Matrix3::identity()).abs().max() < 1e-12);
    }

    #[test]
    fn homogeneous_product_adds_the_translation_last() {
        // (a·x + b·y) + t differs from a·x + (b·y + t) for these values:
        // 0.1 + 0.2 = 0.30000000000000004, then − 0.3 = 5.55e-17; whereas
        // 0.2 − 0.3 = −0.09999999999999998, then + 0.1 = 2.78e-17.
        let m = Matrix3::new(1.0, 1.0, -0.3, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        let r = apply_homogeneous(&m, Vector2::new(0.1, 0.2));
        assert_eq!(r.x, (0.1 + 0.2) - 0.3);
        assert_ne!(r.x, 0.1 + (0.2 - 0.3));
    }

    #[test]
    fn matrix_product_sums_left_to_right() {
        // Entry (0, 0) = (1·0.1 + 1·0.2) + 1·(−0.3): the order is observable.
        let a = Matrix3::new(1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let b = Matrix3::new(0.1, 0.0, 0.0, 0.2, 0.0, 0.0, -0.3, 0.0, 0.0);
        assert_eq!(mat_mul(&a, &b)[(0, 0)], (0.1 + 0.2) - 0.3);
        let a = Matrix3::new(1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0);
        let b = Matrix3::new(9.0, 8.0, 7.0, 6.0, 5.0, 4.0, 3.0, 2.0, 1.0);
        assert_eq!(mat_mul(&a, &b), a * b);
    }

    #[test]
    fn local_helpers_in_a_rotated_frame() {
        let p = Vector2::new(0.0, 0.5);
        assert!(close(
            local_point(FRAC_PI_2, p, Vector2::new(0.0, 0.0)),
            Vector2::new(-0.5, 0.0)
        ));
        assert!(close(
            local_vec(FRAC_PI_2, Vector2::new(0.0, 0.05)),
            Vector2::new(0.05, 0.0)
        ));
    }

    proptest! {
        #[test]
        fn global_point_inverts_local_point(
            theta in -10.0f64..10.0, px in -3.0f64..3.0, py in -3.0f64..3.0,
            qx in -3.0f64..3.0, qy in -3.0f64..3.0,
        ) {
            let p = Vector2::new(px, py);
            let q = Vector2::new(qx, qy);
            let back = global_point(theta, p, local_point(theta, p, q));
            prop_assert!((back - q).abs().max() < 1e-12, "{back:?} vs {q:?}");
        }

        #[test]
        fn global_vec_inverts_local_vec(theta in -10.0f64..10.0, vx in -3.0f64..3.0, vy in -3.0f64..3.0) {
            let v = Vector2::new(vx, vy);
            prop_assert!((global_vec(theta, local_vec(theta, v)) - v).abs().max() < 1e-12);
            prop_assert!((local_vec(theta, global_vec(theta, v)) - v).abs().max() < 1e-12);
        }

        #[test]
        fn local_point_is_local_vec_of_the_offset(
            theta in -10.0f64..10.0, px in -3.0f64..3.0, py in -3.0f64..3.0,
            qx in -3.0f64..3.0, qy in -3.0f64..3.0,
        ) {
            let p = Vector2::new(px, py);
            let q = Vector2::new(qx, qy);
            prop_assert!((local_point(theta, p, q) - local_vec(theta, q - p)).abs().max() < 1e-12);
        }
    }
}
