//! Ready-made models of the project scenes on the generated kernels (used by tests, benches,
//! the simulator and the CLI): the paper's robotic finger (Sect. 2, 6; docs/parameters.md), the
//! human finger variant (Sect. 6), and the model of any parsed scene ([`model_for_scene`]:
//! compiled kernels when the scene is a compiled one, interpreted otherwise;
//! [`model_with_scene_params`]: compiled also when only the parameters outside the kernels
//! differ). A compiled
//! contact scene by name is [`registry::CompiledKernels::named`].

use bf_codegen::spec::Scene;

use crate::kernels::{HumanKernels, PaperKernels};
pub use crate::registry::DynKernels;
use crate::registry::{self, KernelSource};
use crate::{Model, Params, Result};

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

/// [`model_for_scene`] for a scene that may differ from a compiled one (of its name) in the
/// physical parameters the model applies outside its kernels, [`Params`] (the ball's mass and
/// inertia, friction and damping; [`registry::compiled_kernels_match`]): the compiled kernels
/// with the scene's own parameters, where [`model_for_scene`] would interpret the whole scene.
/// The interpreter runs the emitted kernels' arithmetic, so only the speed differs: this is
/// what a perturbed plant (a heavier ball, less friction, more damping) runs on.
pub fn model_with_scene_params(scene: &Scene) -> Result<(Model<DynKernels>, KernelSource)> {
    if let Some((entry, p)) = registry::compiled_kernels_match(scene)
        && let Some(k) = registry::CompiledKernels::<3>::from_entry(entry, p)?
    {
        let params = Params::from_scene(scene)?;
        let k: DynKernels = Box::new(k);
        return Ok((
            Model::from_kernels(k)?.with_params(params),
            KernelSource::Compiled,
        ));
    }
    model_for_scene(scene)
}
