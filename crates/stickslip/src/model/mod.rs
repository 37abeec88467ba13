//! Models: ODE systems with their Jacobians.

pub mod deep_stick;
pub mod drr;
pub mod fast_slip;
pub mod friction;
pub mod lab;
pub mod loading;
pub mod quasi_dynamic;
pub mod robertson;
pub mod saddle_node;
pub mod scales;
pub mod slow_manifold;
pub mod state_law;
pub mod van_der_pol;
pub mod variational;

pub use deep_stick::DeepStick;
pub use drr::{Drr, DrrParams};
pub use friction::Friction;
pub use lab::{LabLaw, LabParameter, LabParametric, LabParams, LabState, LabSystem};
pub use loading::{Loading, Segment};
pub use saddle_node::{SaddleNode, SaddleNodeParams};
pub use scales::{FrictionReference, PhysicalScales};
pub use state_law::StateLaw;
pub use van_der_pol::{VanDerPol, VanDerPolParams};
pub use variational::Variational;
