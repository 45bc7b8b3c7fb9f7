//! Rigid placement of a body frame in the world.

use glam::DVec2;
use serde::{Deserialize, Serialize};

/// A rigid motion: rotate by `angle` about the body origin, then translate by `position`.
///
/// The rotation is kept as the unit complex number `(cos θ, sin θ)` so that applying it is
/// two multiplications and no trigonometry.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// World position of the body origin (its centre of mass).
    pub position: DVec2,
    /// Rotation as `(cos θ, sin θ)`.
    pub rotation: DVec2,
}

impl Default for Pose {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Pose {
    /// No rotation, no translation.
    pub const IDENTITY: Self = Self { position: DVec2::ZERO, rotation: DVec2::X };

    /// A pose from a position and an angle in radians.
    #[must_use]
    pub fn new(position: DVec2, angle: f64) -> Self {
        Self { position, rotation: DVec2::from_angle(angle) }
    }

    /// The rotation angle in radians, in `(−π, π]`.
    #[must_use]
    pub fn angle(&self) -> f64 {
        self.rotation.to_angle()
    }

    /// Rotates a body-frame vector into the world frame.
    #[must_use]
    pub fn rotate(&self, v: DVec2) -> DVec2 {
        self.rotation.rotate(v)
    }

    /// Rotates a world-frame vector into the body frame.
    #[must_use]
    pub fn inverse_rotate(&self, v: DVec2) -> DVec2 {
        DVec2::new(self.rotation.x, -self.rotation.y).rotate(v)
    }

    /// Maps a body-frame point to the world.
    #[must_use]
    pub fn transform_point(&self, p: DVec2) -> DVec2 {
        self.position + self.rotate(p)
    }

    /// Maps a world point into the body frame.
    #[must_use]
    pub fn inverse_transform_point(&self, p: DVec2) -> DVec2 {
        self.inverse_rotate(p - self.position)
    }

    /// The pose of `other`'s frame seen from this frame: `self⁻¹ ∘ other`.
    #[must_use]
    pub fn relative(&self, other: &Pose) -> Pose {
        Pose {
            position: self.inverse_transform_point(other.position),
            rotation: self.inverse_rotate(other.rotation).normalize(),
        }
    }

    /// Whether position and rotation are finite.
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.position.is_finite() && self.rotation.is_finite()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transform_round_trips() {
        let pose = Pose::new(DVec2::new(1.0, -2.0), 0.7);
        let p = DVec2::new(0.3, 0.9);
        assert!((pose.inverse_transform_point(pose.transform_point(p)) - p).length() < 1e-15);
        assert!((pose.angle() - 0.7).abs() < 1e-15);
    }

    #[test]
    fn relative_pose_composes() {
        let a = Pose::new(DVec2::new(1.0, 2.0), 0.4);
        let b = Pose::new(DVec2::new(-3.0, 0.5), -1.1);
        let rel = a.relative(&b);
        let p = DVec2::new(0.2, -0.7);
        let via_world = a.inverse_transform_point(b.transform_point(p));
        assert!((rel.transform_point(p) - via_world).length() < 1e-14);
    }
}
