//! Ready-made models of the project scenes on the generated kernels (used by tests, benches,
//! the simulator and the CLI): the paper's robotic finger (Sect. 2, 6; docs/parameters.md) and the human
//! finger variant (Sect. 6).

use crate::kernels::{HumanKernels, Kernels, PaperKernels};
use crate::{Model, ModelError, Result};

/// The paper scene (`scenes/paper.toml`) with its parameters and default settings.
pub fn paper_scene() -> Result<Model<PaperKernels>> {
    Model::from_kernels(PaperKernels::new())
}

/// The human-finger scene (`scenes/human.toml`) with its default runtime parameters.
pub fn human_scene() -> Result<Model<HumanKernels>> {
    Model::from_kernels(HumanKernels::new())
}

/// A boxed kernel set, for choosing the scene at run time.
pub type DynKernels = Box<dyn Kernels + Send + Sync>;

/// Names of the scenes available through [`scene_by_name`].
pub const SCENES: [&str; 2] = ["paper", "human"];

/// The model of a contact scene by name (`"paper"` or `"human"`).
pub fn scene_by_name(name: &str) -> Result<Model<DynKernels>> {
    let k: DynKernels = match name {
        "paper" => Box::new(PaperKernels::new()),
        "human" => Box::new(HumanKernels::new()),
        _ => {
            return Err(ModelError::Scene {
                scene: name.to_string(),
                message: format!("unknown contact scene; available: {}", SCENES.join(", ")),
            });
        }
    };
    Model::from_kernels(k)
}
