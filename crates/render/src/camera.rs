use visage_camera::{CameraError, Intrinsics, RigidTransform};

use crate::mat4::Mat4;
use crate::projection::{projection_matrix, CAMERA_TO_EYE};
use crate::RenderError;

/// Default near clipping plane, metres: 1 mm, well in front of any face the camera can focus on.
pub const DEFAULT_NEAR: f64 = 1e-3;
/// Default far clipping plane, metres.
pub const DEFAULT_FAR: f64 = 1e3;

/// What the renderer looks through: intrinsics `K`, world → camera pose `V`, clipping planes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Pinhole intrinsics; the rendered image is `intrinsics.width × intrinsics.height`.
    pub intrinsics: Intrinsics,
    /// World → camera transform `x_cam = R · x_world + t` (identity: world coordinates are
    /// camera coordinates).
    pub pose: RigidTransform,
    /// Near clipping plane `z > 0`, metres; geometry closer than this is clipped away.
    pub near: f64,
    /// Far clipping plane, metres.
    pub far: f64,
}

impl Camera {
    /// A camera at the origin looking down +z with [`DEFAULT_NEAR`] / [`DEFAULT_FAR`].
    pub fn new(intrinsics: Intrinsics) -> Result<Camera, RenderError> {
        let cam = Camera {
            intrinsics,
            pose: RigidTransform::IDENTITY,
            near: DEFAULT_NEAR,
            far: DEFAULT_FAR,
        };
        cam.validate()?;
        Ok(cam)
    }

    /// The same camera with another world → camera pose.
    pub fn with_pose(self, pose: RigidTransform) -> Result<Camera, RenderError> {
        let cam = Camera { pose, ..self };
        cam.validate()?;
        Ok(cam)
    }

    /// The same camera with other clipping planes (metres).
    pub fn with_clip_planes(self, near: f64, far: f64) -> Result<Camera, RenderError> {
        let cam = Camera { near, far, ..self };
        cam.validate()?;
        Ok(cam)
    }

    /// Checks intrinsics, pose ([`RigidTransform::validate`]) and `0 < near < far < ∞`.
    pub fn validate(&self) -> Result<(), RenderError> {
        self.intrinsics.validate()?;
        self.pose.validate().map_err(|e| match e {
            CameraError::InvalidTransform { reason } => RenderError::Transform {
                what: "pose",
                reason,
            },
            e => RenderError::Camera(e),
        })?;
        if !(self.near.is_finite()
            && self.far.is_finite()
            && self.near > 0.0
            && self.far > self.near)
        {
            return Err(RenderError::ClipPlanes {
                near: self.near,
                far: self.far,
            });
        }
        Ok(())
    }

    /// `P · F`: camera coordinates (x right, y down, z forward) → OpenGL clip space, where `F`
    /// flips to eye space. The clip-space `w` of a point equals its camera `z`.
    pub fn camera_to_clip(&self) -> Mat4 {
        projection_matrix(&self.intrinsics, self.near, self.far).mul(&CAMERA_TO_EYE)
    }

    /// The view matrix `V` of Eq. (6.1) in OpenGL eye space: `F · [R t]`.
    pub fn view_matrix(&self) -> Mat4 {
        CAMERA_TO_EYE.mul(&Mat4::from_rigid(&self.pose))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_a_pose_that_is_not_a_rotation() {
        let k = Intrinsics::new(64, 48, 60.0, 60.0, 31.5, 23.5).unwrap();
        let camera = Camera::new(k).unwrap();
        let mirror = RigidTransform {
            rotation: [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            translation: [0.0, 0.0, 0.5],
        };
        let err = camera.with_pose(mirror).unwrap_err().to_string();
        assert!(err.contains("pose") && err.contains("reflection"), "{err}");
        let pose = RigidTransform {
            translation: [0.0, 0.0, 0.5],
            ..RigidTransform::IDENTITY
        };
        assert_eq!(camera.with_pose(pose).unwrap().pose, pose);
    }
}
