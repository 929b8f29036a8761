//! Axis-aligned bounds.

use glam::Vec3;

/// Axis-aligned bounding box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Aabb {
    /// The box around `points`, or a zero box at the origin when there are none.
    #[must_use]
    pub fn around(points: &[Vec3]) -> Aabb {
        let mut iter = points.iter();
        let Some(first) = iter.next() else {
            return Aabb {
                min: Vec3::ZERO,
                max: Vec3::ZERO,
            };
        };
        let (min, max) = iter.fold((*first, *first), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        Aabb { min, max }
    }

    /// Length of the diagonal: the character's size `D` that default distances scale with.
    #[must_use]
    pub fn diagonal(&self) -> f32 {
        (self.max - self.min).length()
    }

    /// Centre of the box.
    #[must_use]
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
}
