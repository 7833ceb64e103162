//! The pieces a surface is made of: a ball around one point of a cloud, or one triangle of a
//! mesh. Each is a convex set, so the checker's GJK takes it as it takes a primitive (its
//! support function is in `collision::convex`).

use nalgebra::Vector3;

/// Why a cloud or a mesh was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum SurfaceError {
    /// A coordinate, a radius or a placement is NaN or infinite.
    NonFinite,
    /// A ball radius is zero or negative.
    NonPositiveRadius,
    /// A triangle names a vertex that is not there.
    IndexOutOfRange,
    /// More pieces than the caller's buffers hold, even after the reduction allowed.
    TooManyPieces,
    /// The node buffer is too short for the pieces (it needs [`crate::surface::bvh::nodes_for`]).
    TooFewNodes,
    /// The build's key buffer is shorter than the pieces.
    TooFewKeys,
}

impl core::fmt::Display for SurfaceError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::NonFinite => "value is not a finite number",
            Self::NonPositiveRadius => "radius must be positive",
            Self::IndexOutOfRange => "triangle index out of range",
            Self::TooManyPieces => "more points or triangles than the planner's capacity",
            Self::TooFewNodes => "node buffer too short for the pieces",
            Self::TooFewKeys => "key buffer too short for the pieces",
        })
    }
}

impl core::error::Error for SurfaceError {}

/// An axis-aligned box, `lo` to `hi` (inclusive).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub lo: Vector3<f32>,
    /// Largest corner.
    pub hi: Vector3<f32>,
}

impl Aabb {
    /// The empty box (the identity of [`Aabb::union`]).
    pub const EMPTY: Self = Self {
        lo: Vector3::new(f32::INFINITY, f32::INFINITY, f32::INFINITY),
        hi: Vector3::new(f32::NEG_INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY),
    };

    /// The smallest box holding both.
    #[inline]
    pub fn union(&self, other: &Self) -> Self {
        Self {
            lo: self.lo.zip_map(&other.lo, f32::min),
            hi: self.hi.zip_map(&other.hi, f32::max),
        }
    }

    /// Squared distance from `p` to the box (0 inside).
    #[inline]
    pub fn distance_squared(&self, p: &Vector3<f32>) -> f32 {
        let mut d2 = 0.0;
        for k in 0..3 {
            let below = self.lo[k] - p[k];
            let above = p[k] - self.hi[k];
            let d = below.max(above).max(0.0);
            d2 += d * d;
        }
        d2
    }

    /// Squared distance between the two boxes (0 when they overlap).
    #[inline]
    pub fn distance_squared_to(&self, other: &Self) -> f32 {
        let mut d2 = 0.0;
        for k in 0..3 {
            let d = (self.lo[k] - other.hi[k]).max(other.lo[k] - self.hi[k]).max(0.0);
            d2 += d * d;
        }
        d2
    }

    /// The box around a ball.
    #[inline]
    pub fn around_ball(center: &Vector3<f32>, radius: f32) -> Self {
        Self {
            lo: center.add_scalar(-radius),
            hi: center.add_scalar(radius),
        }
    }

    /// The box around a box with half extents `half` turned by `rotation` about `center`.
    pub fn around_box(center: &Vector3<f32>, rotation: &nalgebra::Matrix3<f32>, half: &Vector3<f32>) -> Self {
        let reach = rotation.abs() * half;
        Self {
            lo: center - reach,
            hi: center + reach,
        }
    }

    /// Volume (0 for the empty box).
    pub fn volume(&self) -> f32 {
        let d = self.hi - self.lo;
        if d.iter().all(|&x| x > 0.0) {
            d.x * d.y * d.z
        } else {
            0.0
        }
    }
}

/// The geometry of one piece, in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Piece {
    /// The ball of `radius` around a cloud point.
    Ball {
        /// The point.
        center: Vector3<f32>,
        /// The cloud's ball radius.
        radius: f32,
    },
    /// A mesh triangle.
    Triangle {
        /// Its corners.
        corners: [Vector3<f32>; 3],
    },
}

/// A piece and the scene obstacle it came from (its index in the scene file), so that a
/// contact can name the obstacle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Element {
    /// The geometry.
    pub piece: Piece,
    /// The obstacle it belongs to.
    pub obstacle: u16,
}

/// Below this squared area (m⁴ times 4) a triangle is degenerate: a segment or a point.
const DEGENERATE: f32 = 1e-20;

fn finite(v: &[f32]) -> Result<(), SurfaceError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(SurfaceError::NonFinite)
    }
}

impl Element {
    /// A cloud point's ball, validated.
    pub fn ball(center: [f32; 3], radius: f32, obstacle: u16) -> Result<Self, SurfaceError> {
        finite(&center)?;
        finite(&[radius])?;
        if radius <= 0.0 {
            return Err(SurfaceError::NonPositiveRadius);
        }
        Ok(Self {
            piece: Piece::Ball {
                center: center.into(),
                radius,
            },
            obstacle,
        })
    }

    /// A mesh triangle, validated; `None` when it is degenerate (the format ignores those).
    pub fn triangle(corners: [[f32; 3]; 3], obstacle: u16) -> Result<Option<Self>, SurfaceError> {
        for c in &corners {
            finite(c)?;
        }
        let [a, b, c] = corners.map(Vector3::from);
        let normal = (b - a).cross(&(c - a));
        if normal.norm_squared().partial_cmp(&DEGENERATE) != Some(core::cmp::Ordering::Greater) {
            return Ok(None);
        }
        Ok(Some(Self {
            piece: Piece::Triangle { corners: [a, b, c] },
            obstacle,
        }))
    }

    /// The smallest axis-aligned box holding the piece.
    #[inline]
    pub fn bounds(&self) -> Aabb {
        match &self.piece {
            Piece::Ball { center, radius } => Aabb {
                lo: center.add_scalar(-radius),
                hi: center.add_scalar(*radius),
            },
            Piece::Triangle { corners: [a, b, c] } => Aabb {
                lo: a.zip_map(b, f32::min).zip_map(c, f32::min),
                hi: a.zip_map(b, f32::max).zip_map(c, f32::max),
            },
        }
    }

    /// A point inside the piece, where the hierarchy sorts it.
    pub fn centroid(&self) -> Vector3<f32> {
        match &self.piece {
            Piece::Ball { center, .. } => *center,
            Piece::Triangle { corners: [a, b, c] } => (a + b + c) / 3.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_are_validated_and_degenerate_triangles_dropped() {
        assert_eq!(
            Element::ball([0.0, f32::NAN, 0.0], 0.01, 0),
            Err(SurfaceError::NonFinite)
        );
        assert_eq!(Element::ball([0.0; 3], 0.0, 0), Err(SurfaceError::NonPositiveRadius));
        let flat = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        assert_eq!(Element::triangle(flat, 0), Ok(None));
        let t = Element::triangle([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], 3)
            .unwrap()
            .unwrap();
        assert_eq!(t.obstacle, 3);
        let b = t.bounds();
        assert_eq!((b.lo, b.hi), (Vector3::zeros(), Vector3::new(1.0, 1.0, 0.0)));
    }
}
