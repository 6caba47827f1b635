//! Ready-made models of the project scenes on the generated kernels (used by tests, benches,
//! the simulator and the CLI): the paper's robotic finger (Sect. 2, 6; docs/parameters.md), the
//! human finger variant (Sect. 6), any compiled contact scene by name ([`scene_by_name`], from
//! the build-time registry `bf_generated::SCENE_KERNELS`), and the model of any parsed scene
//! ([`model_for_scene`]: compiled kernels when the scene is a compiled one, interpreted
//! otherwise).

use bf_codegen::spec::Scene;

use crate::kernels::{HumanKernels, PaperKernels};
pub use crate::registry::DynKernels;
use crate::registry::{self, CompiledKernels, KernelSource};
use crate::{Model, Result};

/// The paper scene (`scenes/paper.toml`) with its parameters and default settings.
pub fn paper_scene() -> Result<Model<PaperKernels>> {
    Model::from_kernels(PaperKernels::new())
}

/// The human-finger scene (`scenes/human.toml`) with its default runtime parameters.
pub fn human_scene() -> Result<Model<HumanKernels>> {
    Model::from_kernels(HumanKernels::new())
}

/// Names of the compiled contact scenes available through [`scene_by_name`] (every
/// `scenes/*.toml` with 3 joints, a ball and the contact kernels).
pub fn scenes() -> Vec<&'static str> {
    registry::compiled_contact_scenes()
}

/// The model of a compiled contact scene by name (default runtime parameters); the error lists
/// the compiled contact scenes.
pub fn scene_by_name(name: &str) -> Result<Model<DynKernels>> {
    let k: DynKernels = Box::new(CompiledKernels::named(name)?);
    Model::from_kernels(k)
}

/// The model of a parsed contact scene and which kernels it runs on (see
/// [`registry::contact_kernels`]); the error names the scene and what it lacks.
pub fn model_for_scene(scene: &Scene) -> Result<(Model<DynKernels>, KernelSource)> {
    let (k, source) = registry::contact_kernels(scene)?;
    Ok((Model::from_kernels(k)?, source))
}
