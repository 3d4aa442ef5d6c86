/// What a depth map's value measures.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DepthKind {
    /// The z coordinate of the surface point (Kinect, RealSense, TUM RGB-D). `X = z · r / r_z`.
    #[default]
    Z,
    /// The Euclidean distance from the camera centre along the unit ray (the paper's `D`,
    /// Eq. (2.2)). `X = D · ρ`.
    Ray,
}

impl DepthKind {
    /// Converts a depth value of this kind at unit ray `ray` into the ray distance `D`.
    ///
    /// For z-depth, `D = z / ρ_z`; `ρ_z > 0` for every pixel of a pinhole camera.
    #[inline]
    pub fn to_ray_distance(self, value: f64, ray: [f64; 3]) -> f64 {
        match self {
            DepthKind::Z => value / ray[2],
            DepthKind::Ray => value,
        }
    }

    /// Converts a ray distance `D` at unit ray `ray` into a depth value of this kind.
    #[inline]
    pub fn from_ray_distance(self, distance: f64, ray: [f64; 3]) -> f64 {
        match self {
            DepthKind::Z => distance * ray[2],
            DepthKind::Ray => distance,
        }
    }
}
