//! The learner-side object shape table (`docs/spec/features.md` §4).

use crate::types::{ACTUATOR_ID, BLUE_ID, RED_ID};

/// Corners (in the object's own frame), segments between corners (pairs of
/// corner indices) and radius of an object, in the order `docs/spec/features.md` §4
/// gives them; the order decides ties in `dist_closing` (§5 step 5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shape {
    pub corners: &'static [[f64; 2]],
    pub segments: &'static [(usize, usize)],
    pub radius: f64,
}

const BOX_SEGMENTS: [(usize, usize); 4] = [(0, 1), (1, 2), (2, 3), (3, 0)];

/// Blue block, 0.5 × 0.1 m.
pub const BLUE_SHAPE: Shape = Shape {
    corners: &[[-0.25, 0.05], [-0.25, -0.05], [0.25, -0.05], [0.25, 0.05]],
    segments: &BOX_SEGMENTS,
    radius: 0.0,
};

/// Red block, 0.3 × 0.3 m.
pub const RED_SHAPE: Shape = Shape {
    corners: &[[-0.15, 0.15], [-0.15, -0.15], [0.15, -0.15], [0.15, 0.15]],
    segments: &BOX_SEGMENTS,
    radius: 0.0,
};

/// Actuator: a single point with radius 0.025 m and no segments.
pub const ACTUATOR_SHAPE: Shape = Shape {
    corners: &[[0.0, 0.0]],
    segments: &[],
    radius: 0.025,
};

/// A bare point (one corner at the origin, no segments, radius 0): the shape
/// [`Shape::of_or_point`] falls back to.
pub const POINT_SHAPE: Shape = Shape {
    corners: &[[0.0, 0.0]],
    segments: &[],
    radius: 0.0,
};

impl Shape {
    /// The table entry for an object id, if there is one.
    #[must_use]
    pub fn of(id: u32) -> Option<&'static Shape> {
        match id {
            BLUE_ID => Some(&BLUE_SHAPE),
            RED_ID => Some(&RED_SHAPE),
            ACTUATOR_ID => Some(&ACTUATOR_SHAPE),
            _ => None,
        }
    }

    /// The table entry, or a bare point for ids without one.
    ///
    /// `parse_frame` rejects such ids, so objects that come from the world
    /// always have a table entry; the fallback only keeps the feature
    /// functions total for hand-built values (the original would have crashed).
    #[must_use]
    pub fn of_or_point(id: u32) -> &'static Shape {
        Self::of(id).unwrap_or(&POINT_SHAPE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table() {
        assert_eq!(Shape::of(15).map(|s| s.corners.len()), Some(4));
        assert_eq!(Shape::of(15).map(|s| s.corners[2]), Some([0.25, -0.05]));
        assert_eq!(Shape::of(27).map(|s| s.corners[0]), Some([-0.15, 0.15]));
        assert_eq!(Shape::of(27).map(|s| s.segments[3]), Some((3, 0)));
        assert_eq!(
            Shape::of(8).map(|s| (s.corners.len(), s.segments.len(), s.radius)),
            Some((1, 0, 0.025))
        );
        assert_eq!(Shape::of(9), None);
        assert_eq!(Shape::of_or_point(9), &POINT_SHAPE);
        assert_eq!(Shape::of_or_point(15), &BLUE_SHAPE);
    }
}
