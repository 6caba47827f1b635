//! Collocation meshes of one phase in normalised time τ ∈ [−1, 1] (paper Sect. 5: the
//! transcription of eq. 57), built from the nodes of [`super::nodes`].
//!
//! * [`Mesh`]: state points and collocation nodes ([`Colloc`]: τ, defect scale s_k, quadrature
//!   weight, differentiation row); [`Mesh::new`] for a [`Scheme`] with N points per phase
//!   (Legendre–Gauss, or equal Radau elements).
//! * [`MeshSpec`]: element boundaries in τ and the number N_e of Legendre–Gauss–Radau points per
//!   element (the state polynomial of element e has degree N_e); serialisable so a refined mesh
//!   can be stored with a solution. [`Mesh::radau_custom`] builds its mesh (defects of eq. 58
//!   with the element scale s_e = h_e / 2).
//! * [`MeshSpec::refined`]: the ph rule of Patterson, Hager & Rao (OCAM 36, 2015) applied to
//!   the element errors of [`super::estimate`]: an element with error e > tol gets
//!   P = ⌈log_N(e / tol)⌉ more points if N + P ≤ N_max, else it is split into
//!   max(2, ⌈(N + P) / N_min⌉) equal elements of N_min points.

use serde::{Deserialize, Serialize};

use super::nodes::{differentiation_matrix, legendre_gauss, legendre_gauss_radau};
use super::problem::Scheme;
use crate::OptimError;
use crate::error::MeshDefect;

/// Largest degree (collocation points) of one hp-Radau element: a refinement raises degrees
/// up to it before it splits elements, and a mesh with a larger degree is refused.
pub const MAX_RADAU_DEGREE: usize = 64;

/// An hp-Radau mesh of one phase.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MeshSpec {
    /// Element boundaries in τ: strictly increasing, first −1, last +1 (one more than
    /// `degrees`).
    pub breaks: Vec<f64>,
    /// LGR points per element (≥ 2); the state polynomial of the element has this degree.
    pub degrees: Vec<usize>,
}

/// Limits of the ph refinement rule ([`MeshSpec::refined`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HpRule {
    /// Points per element after a split (≥ 2).
    pub n_min: usize,
    /// Largest number of points per element reached by raising the degree.
    pub n_max: usize,
}

impl Default for HpRule {
    fn default() -> Self {
        HpRule {
            n_min: 4,
            n_max: 12,
        }
    }
}

impl MeshSpec {
    /// `elements` equal elements of `degree` points each.
    pub fn uniform(elements: usize, degree: usize) -> Result<MeshSpec, OptimError> {
        let k = elements as f64;
        let s = MeshSpec {
            breaks: (0..=elements).map(|e| -1.0 + 2.0 * e as f64 / k).collect(),
            degrees: vec![degree; elements],
        };
        s.validate()?;
        Ok(s)
    }

    /// The mesh [`Mesh::new`] builds for a Radau `scheme` with `points` per phase
    /// (`points.div_ceil(elements).max(2)` points in each of the equal elements).
    pub fn from_scheme(scheme: Scheme, points: usize) -> Result<MeshSpec, OptimError> {
        match scheme {
            Scheme::Radau { elements } if elements > 0 => {
                Self::uniform(elements, points.div_ceil(elements).max(2))
            }
            scheme => Err(OptimError::CustomMeshScheme { scheme }),
        }
    }

    /// Checks the invariants documented on the fields.
    pub fn validate(&self) -> Result<(), OptimError> {
        let bad = |d: MeshDefect| Err(OptimError::InvalidMesh(d));
        if self.degrees.is_empty() || self.breaks.len() != self.degrees.len() + 1 {
            return bad(MeshDefect::BreakCount {
                breaks: self.breaks.len(),
                elements: self.degrees.len(),
            });
        }
        let (first, last) = (self.breaks[0], self.breaks[self.breaks.len() - 1]);
        if first != -1.0 || last != 1.0 {
            return bad(MeshDefect::Span { first, last });
        }
        if let Some(element) = self
            .breaks
            .windows(2)
            .position(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
        {
            return bad(MeshDefect::NotIncreasing { element });
        }
        let mut degrees = self.degrees.iter().enumerate();
        if let Some((element, &degree)) =
            degrees.find(|&(_, &d)| !(2..=MAX_RADAU_DEGREE).contains(&d))
        {
            return bad(MeshDefect::Degree { element, degree });
        }
        Ok(())
    }

    /// Number of elements.
    pub fn n_elements(&self) -> usize {
        self.degrees.len()
    }

    /// Number of collocation points.
    pub fn n_points(&self) -> usize {
        self.degrees.iter().sum()
    }

    /// The mesh after one ph refinement step with element errors `errors` (one per element):
    /// elements with error ≤ `tol` (or a non-finite error, which no refinement can fix) are
    /// kept, the others get more points or are split (see the module docs). Returns `self`
    /// unchanged when every error is ≤ `tol`.
    pub fn refined(&self, errors: &[f64], tol: f64, rule: HpRule) -> MeshSpec {
        let n_min = rule.n_min.max(2);
        let n_max = rule.n_max.max(n_min);
        let mut breaks = vec![self.breaks[0]];
        let mut degrees = Vec::new();
        for (e, &n) in self.degrees.iter().enumerate() {
            let (a, b) = (self.breaks[e], self.breaks[e + 1]);
            let err = errors.get(e).copied().unwrap_or(0.0);
            if err.is_nan() || err <= tol || !err.is_finite() || tol <= 0.0 {
                breaks.push(b);
                degrees.push(n);
                continue;
            }
            // At most 4 × MAX_RADAU_DEGREE points more (an error ratio beyond n^256, 1e77 for
            // n = 2, which no tolerance above 1e-60 gives): a ratio that overflows (a subnormal
            // tolerance) would otherwise saturate the count and wrap n + p.
            let p = (libm::log(err / tol) / libm::log(n as f64))
                .ceil()
                .clamp(1.0, (4 * MAX_RADAU_DEGREE) as f64) as usize;
            if n + p <= n_max {
                breaks.push(b);
                degrees.push(n + p);
            } else {
                let parts = (n + p).div_ceil(n_min).max(2);
                for j in 1..=parts {
                    breaks.push(if j == parts {
                        b
                    } else {
                        a + (b - a) * j as f64 / parts as f64
                    });
                    degrees.push(n_min);
                }
            }
        }
        MeshSpec { breaks, degrees }
    }
}

/// Collocation mesh of one phase (normalised time τ ∈ [−1, 1]).
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    /// τ of the state points (first = −1, last = +1).
    pub state_tau: Vec<f64>,
    /// Collocation nodes.
    pub colloc: Vec<Colloc>,
    /// True for LG: final state by quadrature, and the defects in integral form built from the
    /// `drow`s ([`integration_matrix`](super::transcription::integration_matrix)).
    pub gauss_end: bool,
    /// Elements: ranges of state points (for interpolation).
    pub elements: Vec<std::ops::Range<usize>>,
}

/// One collocation node.
#[derive(Debug, Clone, PartialEq)]
pub struct Colloc {
    /// Index of the node's state point.
    pub state_point: usize,
    /// τ of the node.
    pub tau: f64,
    /// Defect scale s_k.
    pub scale: f64,
    /// Quadrature weight on [−1, 1] for the phase (includes s_k).
    pub weight: f64,
    /// Defect row: (state point, D coefficient).
    pub drow: Vec<(usize, f64)>,
}

impl Mesh {
    /// Builds the mesh for `scheme` with `points` collocation points per phase.
    pub fn new(scheme: Scheme, points: usize) -> Result<Mesh, OptimError> {
        if points < 2 {
            return Err(OptimError::TooFewPoints { points });
        }
        match scheme {
            Scheme::Lg => {
                let (t, w) = legendre_gauss(points);
                let mut sup = vec![-1.0];
                sup.extend(&t);
                let d = differentiation_matrix(&sup);
                let colloc = (0..points)
                    .map(|k| Colloc {
                        state_point: k + 1,
                        tau: t[k],
                        scale: 1.0,
                        weight: w[k],
                        drow: (0..=points).map(|j| (j, d[k + 1][j])).collect(),
                    })
                    .collect();
                let mut state_tau = sup;
                state_tau.push(1.0);
                Ok(Mesh {
                    state_tau,
                    colloc,
                    gauss_end: true,
                    elements: std::iter::once(0..points + 1).collect(),
                })
            }
            Scheme::Radau { .. } => Mesh::from_spec(&MeshSpec::from_scheme(scheme, points)?),
        }
    }

    /// Number of state points.
    pub fn n_state_points(&self) -> usize {
        self.state_tau.len()
    }
}

impl Mesh {
    /// The Radau mesh with element boundaries `breaks` (τ, from −1 to +1) and `degrees[e]` LGR
    /// points in element e (the element's start included, its end excluded; the phase end is
    /// the last state point).
    pub fn radau_custom(breaks: &[f64], degrees: &[usize]) -> Result<Mesh, OptimError> {
        let spec = MeshSpec {
            breaks: breaks.to_vec(),
            degrees: degrees.to_vec(),
        };
        spec.validate()?;
        let mut state_tau = Vec::new();
        let mut colloc = Vec::new();
        let mut ranges = Vec::new();
        for (e, &n) in degrees.iter().enumerate() {
            let (t, w) = legendre_gauss_radau(n);
            let mut sup = t.clone();
            sup.push(1.0);
            let d = differentiation_matrix(&sup);
            let half = 0.5 * (breaks[e + 1] - breaks[e]);
            let base = state_tau.len();
            for j in 0..n {
                let tau = breaks[e] + (t[j] + 1.0) * half;
                state_tau.push(tau);
                colloc.push(Colloc {
                    state_point: base + j,
                    tau,
                    scale: half,
                    weight: w[j] * half,
                    drow: (0..=n).map(|i| (base + i, d[j][i])).collect(),
                });
            }
            ranges.push(base..base + n + 1);
        }
        state_tau.push(1.0);
        Ok(Mesh {
            state_tau,
            colloc,
            gauss_end: false,
            elements: ranges,
        })
    }

    /// [`Mesh::radau_custom`] of a [`MeshSpec`].
    pub fn from_spec(spec: &MeshSpec) -> Result<Mesh, OptimError> {
        Self::radau_custom(&spec.breaks, &spec.degrees)
    }
}
