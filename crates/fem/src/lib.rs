//! P1 finite elements on the image-plane domain Ω and the factor-once fusion solver
//! (paper §2 and §4, as corrected by ERRATA 1–6).
//!
//! Per sequence (set-up): the planar mesh gives the consistent mass M ([`mass_matrix`]), the
//! lumped mass M_l ([`lumped_mass`]), the stiffness L ([`cotan_laplacian`]), the biharmonic
//! stiffness K = Lᵀ M_l⁻¹ L ([`biharmonic`]) and the data mass M_D ([`PixelQuadrature`]); a
//! [`FusionSystem`] factors the frame matrices once. Per frame: a right-hand side
//! ([`PixelQuadrature::assemble_rhs`]) and a solve ([`StreamingSolver::step`]), or one PCG solve
//! for a whole clip ([`solve_clip`]).
//!
//! Units: Ω in reference pixels ([`domain`]), surfaces in metres, λ in reference pixels⁴,
//! μ dimensionless. Vertex fields are faer `Mat<f64>` of shape #V × 3 (x, y, z columns).

#![forbid(unsafe_code)]

mod biharmonic;
mod clip;
mod cotan_laplacian;
pub mod domain;
mod energy;
mod error;
mod factorization;
mod fairing;
mod fairing_constraints;
mod mass_matrix;
mod nested_dissection;
mod pixel_quadrature;
pub mod sparse;
mod streaming;
mod surface_metrics;
mod surface_operators;
mod system;
mod triangle;

pub use biharmonic::biharmonic;
pub use clip::{apply_clip_operator, solve_clip, ClipOptions, ClipReport};
pub use cotan_laplacian::cotan_laplacian;
pub use energy::{clip_energy, frame_energy};
pub use error::FemError;
pub use factorization::{FactorVariant, Factorization};
pub use fairing::{fair, FairingOptions, FairingReport, FairingSystem, Preconditioner};
pub use fairing_constraints::{ConstraintsFileError, FairingConstraint, FairingConstraints};
pub use mass_matrix::{lumped_mass, mass_matrix};
pub use nested_dissection::nested_dissection;
pub use pixel_quadrature::PixelQuadrature;
pub use streaming::{StepReport, StreamingSolver};
pub use surface_metrics::{SurfaceMetrics, SurfaceQuality};
pub use surface_operators::{boundary_vertices, mixed_areas, surface_geometry, SurfaceGeometry};
pub use system::{FusionSystem, Operators, Weights, MAX_WEIGHT};
