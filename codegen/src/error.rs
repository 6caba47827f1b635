//! The generator's error type [`CodegenError`] and the typed defects it carries: what in a
//! scene keeps it from becoming kernels ([`SceneDefect`]), what is wrong with the numbers given
//! to [`crate::eval_all`] ([`InputDefect`]), a request whose expression graph would outgrow
//! its node limit ([`GraphTooLarge`]), and the generator's own inconsistencies
//! ([`InternalDefect`], bugs). The defects are descriptions, not causes: their text is part of
//! the variant's message; only a real error of another library (syn's parse error) is a
//! `source()`.

use std::fmt;

/// Errors of the generator.
#[derive(Debug, thiserror::Error)]
pub enum CodegenError {
    /// The scene cannot be turned into kernels (unknown kernel or parameter, missing ball, …).
    #[error("scene error: {0}")]
    Scene(SceneDefect),
    /// Bad numeric input to [`crate::eval_all`] (wrong length, non-finite value).
    #[error("input error: {0}")]
    Input(InputDefect),
    /// Emit settings that cannot be combined (e.g. fused multiply-add in a no_std module).
    #[error("emit settings: {0}")]
    Settings(&'static str),
    /// The request's expression graph would exceed its node limit ([`crate::graph::Graph::limit`]).
    #[error("{0}")]
    TooLarge(GraphTooLarge),
    /// A bug in the generator (an inconsistency between its own parts).
    #[error("internal generator error: {0}")]
    Internal(InternalDefect),
    /// A bug in the generator: Rust text it produced (or carries) does not parse.
    #[cfg(feature = "emit")]
    #[error("internal generator error: the Rust text of {what} does not parse")]
    Unparsable {
        /// Which text (`trig.rs`, `emitted code`, …).
        what: &'static str,
        /// syn's parse error.
        #[source]
        source: syn::Error,
    },
}

impl From<SceneDefect> for CodegenError {
    fn from(d: SceneDefect) -> Self {
        CodegenError::Scene(d)
    }
}

impl From<InputDefect> for CodegenError {
    fn from(d: InputDefect) -> Self {
        CodegenError::Input(d)
    }
}

impl From<InternalDefect> for CodegenError {
    fn from(d: InternalDefect) -> Self {
        CodegenError::Internal(d)
    }
}

#[cfg(feature = "emit")]
impl CodegenError {
    /// [`CodegenError::Unparsable`] for the text `what`, for `map_err`.
    pub(crate) fn unparsable(what: &'static str) -> impl FnOnce(syn::Error) -> CodegenError {
        move |source| CodegenError::Unparsable { what, source }
    }
}

/// Peak memory per graph node of generating or evaluating kernels (bytes): the graph, its memo
/// table and the tape or the emitted text (measured 250–370 bytes on chains of 10–40 joints,
/// more on the larger ones).
pub const BYTES_PER_NODE: usize = 400;

/// A request whose expression graph would hold more nodes than its limit: which quantity was
/// being built, on how many joints, and what to do about it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "{what}: the expression graph of this {joints}-joint robot would hold more than {limit} \
     nodes, about {} of memory at {BYTES_PER_NODE} bytes a node; {advice}; or, if the \
     machine has the memory, raise the limit (`--max-graph-nodes`, `Builder::max_graph_nodes`)",
    memory(*limit)
)]
pub struct GraphTooLarge {
    /// What was being built (`kernel `christoffel``, `eval`, a node function).
    pub what: String,
    /// The robot's joints.
    pub joints: usize,
    /// The graph's node limit.
    pub limit: usize,
    /// What makes the request smaller.
    pub advice: &'static str,
}

/// The peak memory of a graph of `nodes` nodes ([`BYTES_PER_NODE`]) in GiB, or MiB below one.
fn memory(nodes: usize) -> String {
    let bytes = nodes as f64 * BYTES_PER_NODE as f64;
    let gib = bytes / (1u64 << 30) as f64;
    if gib >= 1.0 {
        format!("{gib:.1} GiB")
    } else {
        format!("{:.0} MiB", bytes / (1u64 << 20) as f64)
    }
}

/// Why a scene cannot be turned into kernels.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SceneDefect {
    /// The DH table is empty.
    #[error("the scene has no links")]
    NoLinks,
    /// The scene has no `[ball]` table (contact quantities, node functions).
    #[error("the scene has no [ball]")]
    NoBall,
    /// The scene has no `[contact]` table (node functions).
    #[error("the scene has no [contact]")]
    NoContact,
    /// A contact kernel was requested without both `[ball]` and `[contact]`.
    #[error("contact kernels need both [ball] and [contact] in the scene")]
    NoBallOrContact,
    /// A `runtime_parameters` entry names no scene constant.
    #[error("unknown runtime parameter `{name}`; known constants: {}", known.join(", "))]
    UnknownRuntimeParameter {
        /// The name given.
        name: String,
        /// The scene's constants.
        known: Vec<String>,
    },
    /// A `runtime_parameters` entry appears twice.
    #[error("runtime parameter `{name}` listed twice")]
    RuntimeParameterTwice {
        /// The repeated name.
        name: String,
    },
    /// A kernel name that the generator does not know.
    #[error("unknown kernel `{name}`{}; known kernels: {}", if *in_list { " in `kernels`" } else { "" }, known.join(", "))]
    UnknownKernel {
        /// The name given.
        name: String,
        /// Whether it comes from the scene's `kernels` list (else from a caller's request).
        in_list: bool,
        /// The kernels the generator knows.
        known: &'static [&'static str],
    },
    /// A kernel appears twice in the scene's `kernels` list.
    #[error("kernel `{name}` listed twice in `kernels`")]
    KernelTwice {
        /// The repeated name.
        name: String,
    },
    /// A rotation about an axis other than x, y, z.
    #[error("rotation axis must be \"x\", \"y\" or \"z\", got {axis:?}")]
    RotationAxis {
        /// The axis given.
        axis: String,
    },
    /// `contact.kind` is neither `segment` nor `tip`.
    #[error("contact.kind must be \"segment\" or \"tip\", got {kind:?}")]
    ContactKind {
        /// The kind given.
        kind: String,
    },
    /// Segment contact on a modified DH table (which does not hold the last link's length).
    #[error(
        "contact.kind = \"segment\" needs the last link's length a_n, which a modified DH table \
         does not hold; use kind = \"tip\""
    )]
    SegmentContactModifiedDh,
    /// Segment contact whose segment start (where the last link leaves its joint's axis, in
    /// tip-frame coordinates: `Scene::contact_segment_start`) is not on the tip frame's x axis
    /// behind the tip (the segment p_e − ℓ e_x … p_e must end at the last joint's axis).
    #[error(
        "contact.kind = \"segment\" needs the point where the last link leaves its joint's axis \
         on the tip frame's x axis, behind the tip (the contact segment runs from there to the \
         tip along e_x); that point sits at {start:?} in tip-frame coordinates; turn or move \
         the [tool] (the tip link) so that its x axis points along the last link, or use \
         kind = \"tip\""
    )]
    SegmentContactGeometry {
        /// The segment's start in tip-frame coordinates.
        start: [f64; 3],
    },
    /// Segment contact with a runtime parameter that moves the segment whose length the
    /// kernels bake in: a tool translation, or a_n with a tool that is not the identity.
    #[error(
        "contact.kind = \"segment\": runtime parameter `{name}` would change the contact \
         segment, whose length the kernels bake in at generation time; keep it baked or use \
         kind = \"tip\""
    )]
    SegmentLengthRuntime {
        /// The runtime parameter.
        name: String,
    },
    /// Folding the scene's values gives a non-finite constant in a kernel (it would be emitted
    /// as `f64::INFINITY`).
    #[error(
        "{what}: folding the scene values gives the non-finite constant {value}; the values \
         are out of range for f64 arithmetic (extreme values: {extremes})"
    )]
    NonFiniteConstant {
        /// Which kernel (or group of kernels).
        what: String,
        /// The folded constant.
        value: f64,
        /// The scene's largest and smallest nonzero constants.
        extremes: ExtremeValues,
    },
}

/// What is wrong with the numbers given to [`crate::eval_all`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InputDefect {
    /// q or q̇ does not have one entry per joint.
    #[error("the scene has {joints} joints but q has {q} and qd has {qd} entries")]
    JointCount {
        /// The scene's joints.
        joints: usize,
        /// Entries of q.
        q: usize,
        /// Entries of q̇.
        qd: usize,
    },
    /// An input is not finite.
    #[error("{what} contains a non-finite value {value} (entry {index})")]
    NonFinite {
        /// Which input (`q`, `qd`, `omega`, `eps`).
        what: &'static str,
        /// Index of the first non-finite entry.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// A computed quantity is not finite at this state.
    #[error(
        "{what} is not finite ({value}) at this state: the state or the scene values overflow \
         f64 arithmetic (extreme scene values: {extremes})"
    )]
    NonFiniteResult {
        /// The quantity (an [`crate::EvalOutput`] name).
        what: String,
        /// Its first non-finite entry.
        value: f64,
        /// The scene's largest and smallest nonzero constants.
        extremes: ExtremeValues,
    },
}

/// An inconsistency between the generator's own parts (a bug).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InternalDefect {
    /// A kernel's output reads a graph variable that no kernel argument holds.
    #[error("kernel `{kernel}` reads graph variable {variable}, which no kernel argument holds")]
    UnboundVariable {
        /// The kernel.
        kernel: String,
        /// The graph variable index.
        variable: u32,
    },
    /// A kernel's output reads an argument the kernel does not take.
    #[error("kernel `{kernel}` reads {argument} but does not take it as an argument")]
    MissingArgument {
        /// The kernel.
        kernel: String,
        /// The argument it reads (the `Debug` name of its `kernels::Arg`; this module sits
        /// below `kernels`).
        argument: String,
    },
    /// A placeholder the emitter put into formatted code is not found in it again.
    #[error("{what}: placeholder `{marker}` not found")]
    MissingPlaceholder {
        /// Which text (`node kernels`, …).
        what: &'static str,
        /// The placeholder.
        marker: String,
    },
    /// Any other inconsistency, named by a fixed description.
    #[error("{0}")]
    Other(&'static str),
}

/// The largest and the smallest nonzero constants of a scene (name, value), for messages about
/// values out of range of f64 arithmetic; shown as `name = value` in scientific notation.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ExtremeValues(pub Vec<(String, f64)>);

impl fmt::Display for ExtremeValues {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, (k, v)) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{k} = {v:e}")?;
        }
        Ok(())
    }
}

impl From<&'static str> for InternalDefect {
    fn from(description: &'static str) -> Self {
        InternalDefect::Other(description)
    }
}
