//! Models: ODE systems with their Jacobians.

pub mod deep_stick;
pub mod drr;
pub mod fast_slip;
pub mod friction;
pub mod lab;
pub mod loading;
pub mod periodic;
pub mod quasi_dynamic;
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
pub use periodic::{ForcedDrr, PeriodicLoading, TimeOrigin};
pub use saddle_node::{SaddleNode, SaddleNodeParams};
pub use scales::{FrictionReference, PhysicalScales};
pub use state_law::StateLaw;
pub use van_der_pol::{VanDerPol, VanDerPolParams};
pub use variational::Variational;

/// The kind of a scene's model (`"model": {"kind": ...}`); [`ModelKind::name`] is its name in
/// the scene and the messages. Laboratory scenes (`"kind": "lab"`, `scene::lab::KIND`) have
/// a scene form of their own, which `scene::parse_any` tells apart by that kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelKind {
    /// "drr": the spring-slider (the default).
    Drr,
    /// "saddle_node": the tilted saddle-node normal form ([`SaddleNode`]).
    SaddleNode,
    /// "van_der_pol": the relaxation oscillator ([`VanDerPol`]).
    VanDerPol,
}

impl ModelKind {
    /// Every kind, in the order the messages list them.
    pub const ALL: [ModelKind; 3] = [ModelKind::Drr, ModelKind::SaddleNode, ModelKind::VanDerPol];

    /// Its name in the scene, e.g. "saddle_node".
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Drr => "drr",
            ModelKind::SaddleNode => "saddle_node",
            ModelKind::VanDerPol => "van_der_pol",
        }
    }

    /// The kind named `name` in a scene, if any.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// The number of state components (and of noise amplitudes).
    pub fn dimension(self) -> usize {
        match self {
            ModelKind::Drr => 3,
            ModelKind::SaddleNode => 1,
            ModelKind::VanDerPol => 2,
        }
    }
}

impl std::fmt::Display for ModelKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
