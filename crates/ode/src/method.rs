//! The methods by name: one row per method with its name and its dense-output order, the
//! facts the integrators themselves report ([`Integrator::name`](crate::integrate::Integrator::name),
//! [`Integrator::max_dense_order`](crate::integrate::Integrator::max_dense_order)). It sits
//! below [`crate::integrate`] and [`crate::sundials`], which read it; the rest of the method
//! table (what each method accepts, one constructor for all) is
//! [`crate::solver`], which re-exports [`Method`].

use serde::Serialize;

/// Defines [`Method`], its names and dense-output orders from one list of
/// `Variant = "name", dense_order N;` rows, so that [`Method::ALL`], [`Method::name`] and
/// [`Method::dense_order`] cannot miss a variant: a method is added by adding its row (and its
/// [`Method::capabilities`](crate::solver::Method::capabilities) arm, which the compiler asks
/// for).
macro_rules! methods {
    ($($(#[$doc:meta])* $variant:ident = $name:literal, dense_order $order:literal;)*) => {
        /// The integration methods, by name.
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        pub enum Method {
            $($(#[$doc])* $variant,)*
        }

        impl Method {
            /// Every method with its name, in the order of the definition.
            pub const ALL: [(&'static str, Method); [$($name),*].len()] =
                [$(($name, Method::$variant)),*];

            /// The name, e.g. "cvode-bdf" (also the integrator's name in errors).
            pub const fn name(self) -> &'static str {
                match self {
                    $(Method::$variant => $name,)*
                }
            }

            /// The largest k that `dense(t, k)` can accept after a step (CVODE: up to the
            /// order of the last step, at most this; before the first step every method takes
            /// k ≤ 1 only). [`Integrator::max_dense_order`] gives the bound in force.
            ///
            /// [`Integrator::max_dense_order`]: crate::integrate::Integrator::max_dense_order
            pub const fn dense_order(self) -> u32 {
                match self {
                    $(Method::$variant => $order,)*
                }
            }
        }
    };
}

methods! {
    /// CVODE, variable-order BDF (stiff): orders up to 5.
    CvodeBdf = "cvode-bdf", dense_order 5;
    /// CVODE, Adams–Moulton (non-stiff): orders up to 12.
    CvodeAdams = "cvode-adams", dense_order 12;
    /// ARKStep, diagonally implicit Runge–Kutta (stiff); ARKODE's Hermite interpolant.
    ArkodeDirk = "arkode-dirk", dense_order 5;
    /// ARKStep, implicit–explicit: the system's explicit part explicit, its implicit part
    /// implicit (stiff; [`ImexSystem`](crate::integrate::ImexSystem)); ARKODE's
    /// Lagrange interpolant of its default degree 3 (see `Solver::arkstep_imex`).
    ArkodeImex = "arkode-imex", dense_order 3;
    /// ARKStep, explicit Runge–Kutta (non-stiff); ARKODE's Hermite interpolant.
    ArkodeErk = "arkode-erk", dense_order 5;
    /// This crate's own Radau IIA of order 5 (stiff, pure Rust); its cubic collocation
    /// polynomial.
    Radau5 = "radau5", dense_order 3;
    /// This crate's own Rosenbrock method Rodas5P (stiff, pure Rust); its dense output of
    /// degree 4.
    Rodas5p = "rodas5p", dense_order 4;
    /// This crate's own extrapolation with stiffness switching (linearly implicit Euler /
    /// modified midpoint, the family the paper used; pure Rust).
    Extrapolation = "extrapolation", dense_order 3;
}

impl Serialize for Method {
    /// The name, e.g. "cvode-bdf".
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.name())
    }
}

impl std::fmt::Display for Method {
    /// The name (padded to a width if one is given).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.name())
    }
}
