//! Ready-made models of the project scenes on the generated kernels (used by tests, benches,
//! the simulator and the CLI): the paper's robotic finger (Sect. 2, 6; docs/parameters.md), the
//! human finger variant (Sect. 6), and the model of any parsed scene ([`model_for_scene`]:
//! compiled kernels when the scene is a compiled one, or one with another ball mass, friction
//! or damping, interpreted otherwise). A compiled
//! contact scene by name is [`registry::CompiledKernels::named`].

use bf_codegen::spec::Scene;

use crate::kernels::{HumanKernels, PaperKernels};
pub use crate::registry::DynKernels;
use crate::registry::{self, KernelSource};
use crate::{Model, Result};

/// The paper scene (`scenes/paper.toml`) with its parameters and default settings.
pub fn paper_scene() -> Result<Model<PaperKernels>> {
    Model::from_kernels(PaperKernels::new())
}

/// The human-finger scene (`scenes/human.toml`) with its default runtime parameters.
pub fn human_scene() -> Result<Model<HumanKernels>> {
    Model::from_kernels(HumanKernels::new())
}

/// The model of a parsed contact scene and which kernels it runs on (see
/// [`registry::contact_kernels`]); the error names the scene and what it lacks.
pub fn model_for_scene(scene: &Scene) -> Result<(Model<DynKernels>, KernelSource)> {
    let (k, source) = registry::contact_kernels(scene)?;
    Ok((Model::from_kernels(k)?, source))
}
