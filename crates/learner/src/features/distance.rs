//! Distance and closing between two objects (`docs/spec/features.md` §5).

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use super::round::{r3, Precision};
use super::shape::Shape;
use super::transform::global_point;
use crate::types::{ObjectState, TrackedObject};

/// What `dist_closing` needs of an object: id (for the shape table), position,
/// yaw and displacement since its previous state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Body {
    pub id: u32,
    pub position: Vector2<f64>,
    pub theta: f64,
    pub displacement: Vector2<f64>,
}

impl Body {
    /// A body without displacement (closing is then irrelevant; the clamped
    /// [`dist`] uses this).
    #[must_use]
    pub fn at_rest(id: u32, s: &ObjectState) -> Self {
        Self {
            id,
            position: s.position(),
            theta: s.theta,
            displacement: Vector2::zeros(),
        }
    }
}

impl From<&TrackedObject> for Body {
    fn from(o: &TrackedObject) -> Self {
        Self {
            id: o.id,
            position: o.s.position(),
            theta: o.s.theta,
            displacement: o.velocity(),
        }
    }
}

/// Result of [`dist_closing`], both 3-decimal rounded.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DistClosing {
    /// Signed distance (negative on overlap, not clamped).
    pub distance: f64,
    /// `n̂ · (v_B − v_A)`: negative when approaching, positive when separating.
    pub closing: f64,
}

/// `|v|` as `sqrt(x² + y²)`, not `hypot`, to match the original's norm.
fn norm(v: Vector2<f64>) -> f64 {
    (v.x * v.x + v.y * v.y).sqrt()
}

/// Closest point to `c` on the segment from `a` to `b` (`docs/spec/features.md` §5 step 4).
#[must_use]
pub fn closest_point_on_segment(a: Vector2<f64>, b: Vector2<f64>, c: Vector2<f64>) -> Vector2<f64> {
    let ab = b - a;
    let l2 = ab.x * ab.x + ab.y * ab.y;
    if l2 == 0.0 {
        return a;
    }
    let ac = c - a;
    let t = (ac.x * ab.x + ac.y * ab.y) / l2;
    if t < 0.0 {
        a
    } else if t > 1.0 {
        b
    } else {
        a + ab * t
    }
}

/// An entry of the L1 / L2 lists: distance, closest segment point `q`, corner `c`.
#[derive(Clone, Copy)]
struct Entry {
    dist: f64,
    q: Vector2<f64>,
    c: Vector2<f64>,
}

fn world_corners(body: &Body, shape: &Shape) -> Vec<Vector2<f64>> {
    shape
        .corners
        .iter()
        .map(|&[x, y]| global_point(body.theta, body.position, Vector2::new(x, y)))
        .collect()
}

/// The first smallest entry over every corner of `from` (in order) and every
/// segment of `to` (in order), distances reduced by `from_radius`
/// (`docs/spec/features.md` §5 steps 2, 3, 5).
fn first_min(
    from: &[Vector2<f64>],
    from_radius: f64,
    to: &[Vector2<f64>],
    to_segments: &[(usize, usize)],
) -> Option<Entry> {
    let mut best: Option<Entry> = None;
    for &c in from {
        for &(i, j) in to_segments {
            let (Some(&a), Some(&b)) = (to.get(i), to.get(j)) else {
                continue;
            };
            let q = closest_point_on_segment(a, b, c);
            let dist = norm(c - q) - from_radius;
            // Strict `<`: among equal distances the first entry stays.
            if best.is_none_or(|e| dist < e.dist) {
                best = Some(Entry { dist, q, c });
            }
        }
    }
    best
}

/// Unrounded distance and unit normal (pointing from A towards B, or zero),
/// with the shapes given explicitly.
fn contact(a: &Body, sa: &Shape, b: &Body, sb: &Shape) -> (f64, Vector2<f64>) {
    let (ca, cb) = (world_corners(a, sa), world_corners(b, sb));
    let l1 = first_min(&ca, sa.radius, &cb, sb.segments);
    let l2 = first_min(&cb, sb.radius, &ca, sa.segments);
    // docs/spec/features.md §5 step 5: L1 only when strictly closer; on equality L2 wins.
    // The normal always points from A to B: L1's corner c is A's, L2's is B's.
    let (dist, n) = match (l1, l2) {
        (Some(e1), Some(e2)) if e1.dist < e2.dist => (e1.dist, e1.q - e1.c),
        (_, Some(e2)) => (e2.dist, e2.c - e2.q),
        (Some(e1), None) => (e1.dist, e1.q - e1.c),
        (None, None) => (0.0, Vector2::zeros()),
    };
    let len = norm(n);
    let n = if len > 0.0 { n / len } else { n };
    (dist, n)
}

fn contact_by_id(a: &Body, b: &Body) -> (f64, Vector2<f64>) {
    contact(a, Shape::of_or_point(a.id), b, Shape::of_or_point(b.id))
}

fn closing(n: Vector2<f64>, a: &Body, b: &Body, precision: Precision) -> f64 {
    let dv = b.displacement - a.displacement;
    precision.round(n.x * dv.x + n.y * dv.y)
}

/// `dist_closing(A, B)` (`docs/spec/features.md` §5): rounded signed distance between A
/// (the reference) and B, and the rounded closing speed along the normal from
/// A towards B.
#[must_use]
pub fn dist_closing(a: &Body, b: &Body) -> DistClosing {
    dist_closing_at(a, b, Precision::Thesis)
}

/// [`dist_closing`] rounded at `precision`.
#[must_use]
pub fn dist_closing_at(a: &Body, b: &Body, precision: Precision) -> DistClosing {
    let (dist, n) = contact_by_id(a, b);
    DistClosing {
        distance: precision.round(dist),
        closing: closing(n, a, b, precision),
    }
}

/// The clamped variant `dist(A, B) = r3(max(dist, 0))` (`docs/spec/features.md` §5;
/// only the interaction model's circling uses it).
#[must_use]
pub fn dist(a_id: u32, a: &ObjectState, b_id: u32, b: &ObjectState) -> f64 {
    let (d, _) = contact_by_id(&Body::at_rest(a_id, a), &Body::at_rest(b_id, b));
    r3(d.max(0.0))
}

#[cfg(test)]
mod tests {
    use std::f64::consts::FRAC_PI_2;

    use proptest::prelude::*;

    use super::*;
    use crate::types::{ACTUATOR_ID, BLUE_ID, RED_ID};

    fn body(id: u32, x: f64, y: f64, theta: f64, vx: f64, vy: f64) -> Body {
        Body {
            id,
            position: Vector2::new(x, y),
            theta,
            displacement: Vector2::new(vx, vy),
        }
    }

    fn assert_dc(got: DistClosing, distance: f64, closing: f64) {
        assert!(
            (got.distance - distance).abs() < 1e-4 && (got.closing - closing).abs() < 1e-4,
            "got {got:?}, expected ({distance}, {closing})"
        );
    }

    /// docs/spec/features.md §7 example 2.
    #[test]
    fn example_2_dist_closing() {
        let act = body(ACTUATOR_ID, 0.0, 0.0, 0.0, 0.0, 0.5);
        assert_dc(
            dist_closing(&body(RED_ID, 0.0, 0.5, 0.0, 0.0, 0.0), &act),
            0.325,
            -0.5,
        );
        assert_dc(
            dist_closing(&body(BLUE_ID, 0.0, 0.5, 0.0, 0.0, 0.0), &act),
            0.425,
            -0.5,
        );

        let red = body(RED_ID, 0.0, 0.0, 0.0, 0.0, 0.5);
        assert_dc(
            dist_closing(&body(BLUE_ID, 0.0, 0.5, 0.0, 0.0, 0.0), &red),
            0.3,
            -0.5,
        );
        assert_dc(
            dist_closing(&body(BLUE_ID, 0.0, 0.5, FRAC_PI_2, 0.0, 0.0), &red),
            0.1,
            -0.5,
        );
        let red_turned = body(RED_ID, 0.0, 0.0, FRAC_PI_2, 0.0, 0.5);
        assert_dc(
            dist_closing(&body(BLUE_ID, 0.0, 0.5, 0.0, 0.0, 0.0), &red_turned),
            0.3,
            -0.5,
        );
    }

    /// docs/spec/features.md §7 example 3.
    #[test]
    fn example_3_point_to_segment() {
        let q = closest_point_on_segment(
            Vector2::new(-0.25, 0.45),
            Vector2::new(0.25, 0.45),
            Vector2::zeros(),
        );
        assert!((q - Vector2::new(0.0, 0.45)).abs().max() < 1e-12);
        assert!((norm(q) - 0.45).abs() < 1e-12);
        assert!((norm(q) - 0.025 - 0.425).abs() < 1e-12);
        let c = Vector2::new(-0.3, 0.5);
        let q = closest_point_on_segment(Vector2::new(-0.25, 0.45), Vector2::new(-0.25, 0.55), c);
        assert!((q - Vector2::new(-0.25, 0.5)).abs().max() < 1e-12);
        assert!((norm(c - q) - 0.05).abs() < 1e-12);
    }

    #[test]
    fn point_to_segment_clamps_and_handles_degenerate_segments() {
        let (a, b) = (Vector2::new(0.0, 0.0), Vector2::new(1.0, 0.0));
        assert_eq!(closest_point_on_segment(a, b, Vector2::new(-2.0, 1.0)), a);
        assert_eq!(closest_point_on_segment(a, b, Vector2::new(3.0, -1.0)), b);
        assert_eq!(closest_point_on_segment(a, a, Vector2::new(3.0, -1.0)), a);
    }

    #[test]
    fn normal_points_from_reference_to_other() {
        // Actuator right of the block moving right: separating (positive).
        let blue = body(BLUE_ID, 0.0, 0.0, 0.0, 0.0, 0.0);
        let right = body(ACTUATOR_ID, 0.4, 0.0, 0.0, 0.005, 0.0);
        assert_dc(dist_closing(&blue, &right), 0.125, 0.005);
        // Actuator below the block moving up: approaching (negative).
        let below = body(ACTUATOR_ID, 0.0, -0.2, 0.0, 0.0, 0.005);
        assert_dc(dist_closing(&blue, &below), 0.125, -0.005);
        // Only the reference moves, towards the actuator: also approaching.
        let moving_blue = body(BLUE_ID, 0.0, 0.0, 0.0, 0.0, -0.003);
        let still = body(ACTUATOR_ID, 0.0, -0.2, 0.0, 0.0, 0.0);
        assert_dc(dist_closing(&moving_blue, &still), 0.125, -0.003);
        // Swapping A and B mirrors the normal; closing stays the same.
        assert_dc(dist_closing(&below, &blue), 0.125, -0.005);
    }

    /// Shapes whose minima tie exactly (dyadic numbers) with different
    /// normals. A is a segment from (0, 0) to (1, 0). B, shifted by `dx`, has a
    /// vertical segment at x = 2 + dx and a loose corner (0.5 + dx, 1) that ends
    /// no segment. L1 (A's corner (1, 0) to B's segment) gives 1 + dx with
    /// normal +x; L2 (B's loose corner to A's segment) gives 1 with normal +y.
    /// B moves by (0.01, 0.02), so the closing tells which normal was used.
    fn tie_case(dx: f64) -> (f64, f64) {
        const A: Shape = Shape {
            corners: &[[0.0, 0.0], [1.0, 0.0]],
            segments: &[(0, 1)],
            radius: 0.0,
        };
        const B: Shape = Shape {
            corners: &[[2.0, -1.0], [2.0, 3.0], [0.5, 1.0]],
            segments: &[(0, 1)],
            radius: 0.0,
        };
        let a = body(0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let b = body(0, dx, 0.0, 0.0, 0.01, 0.02);
        let (d, n) = contact(&a, &A, &b, &B);
        (d, closing(n, &a, &b, Precision::Thesis))
    }

    #[test]
    fn equal_minima_use_l2() {
        assert_eq!(tie_case(0.0), (1.0, 0.02));
    }

    #[test]
    fn strictly_smaller_l1_wins_otherwise_l2() {
        assert_eq!(tie_case(-0.25), (0.75, 0.01));
        assert_eq!(tie_case(0.25), (1.0, 0.02));
    }

    #[test]
    fn first_smallest_entry_wins_within_a_list() {
        // B's only corner lies midway between A's two parallel segments
        // y = −1 and y = 1; the first of them in order must win.
        let a_shape = Shape {
            corners: &[[-1.0, -1.0], [1.0, -1.0], [-1.0, 1.0], [1.0, 1.0]],
            segments: &[(0, 1), (2, 3)],
            radius: 0.0,
        };
        let b_shape = Shape {
            corners: &[[0.0, 0.0]],
            segments: &[],
            radius: 0.0,
        };
        let a = body(0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let b = body(0, 0.0, 0.0, 0.0, 0.0, 0.02);
        let (d, n) = contact(&a, &a_shape, &b, &b_shape);
        assert_eq!(d, 1.0);
        // The first segment (y = −1) wins: n = c − q = (0, 0) − (0, −1) = +y.
        assert_eq!(n, Vector2::new(0.0, 1.0));
        assert_eq!(closing(n, &a, &b, Precision::Thesis), 0.02);
    }

    proptest! {
        #[test]
        fn clamped_dist_is_never_negative(
            x in -1.0f64..1.0, y in -1.0f64..1.0, t in -4.0f64..4.0,
            ax in -1.0f64..1.0, ay in -1.0f64..1.0,
        ) {
            let block = ObjectState::new(x, y, t);
            let act = ObjectState::new(ax, ay, 0.0);
            let d = dist(BLUE_ID, &block, ACTUATOR_ID, &act);
            prop_assert!(d >= 0.0);
            let signed = dist_closing(&Body::at_rest(BLUE_ID, &block), &Body::at_rest(ACTUATOR_ID, &act)).distance;
            prop_assert_eq!(d, r3(signed.max(0.0)));
        }
    }

    #[test]
    fn overlap_gives_negative_signed_but_zero_clamped_distance() {
        let block = ObjectState::new(0.0, 0.0, 0.0);
        let act = ObjectState::new(0.0, -0.06, 0.0);
        let signed = dist_closing(
            &Body::at_rest(BLUE_ID, &block),
            &Body::at_rest(ACTUATOR_ID, &act),
        );
        assert!((signed.distance - -0.015).abs() < 1e-12);
        assert_eq!(dist(BLUE_ID, &block, ACTUATOR_ID, &act), 0.0);
    }

    #[test]
    fn two_points_have_distance_zero_and_no_normal() {
        let a = body(ACTUATOR_ID, 0.0, 0.0, 0.0, 0.0, 0.0);
        let b = body(ACTUATOR_ID, 1.0, 1.0, 0.0, 0.3, 0.3);
        assert_eq!(
            dist_closing(&a, &b),
            DistClosing {
                distance: 0.0,
                closing: 0.0
            }
        );
    }
}
