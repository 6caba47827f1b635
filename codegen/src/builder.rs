//! The build-script API: compiled kernels of a robot in the user's own crate, in the manner of
//! `prost-build`. A `build.rs` names a URDF (or a TOML scene file), chooses the chain, the
//! kernels and the float type, and writes the module into `OUT_DIR`; the crate `include!`s it
//! (docs/your-robot.md, examples/own-crate/). The kernels are those of [`crate::generate_with`]
//! (eq. 22a, 67–79 and the inverse-dynamics family; contact eq. 2–13 for scenes with a ball).
//!
//! ```no_run
//! // build.rs
//! let out = std::env::var("OUT_DIR").unwrap();
//! let module = bf_codegen::Builder::new("robot.urdf")
//!     .base("base_link")
//!     .tip("tool0")
//!     .kernels(["mass_cqd_g", "forward_dynamics"])
//!     .emit_to(&out)
//!     .unwrap_or_else(|e| panic!("{e}"));
//! // src/main.rs: mod robot { include!(concat!(env!("OUT_DIR"), "/ur5.rs")); }
//! # let _ = module;
//! ```

use std::path::{Path, PathBuf};

use crate::emit::{EmitSettings, FloatTy};
use crate::spec::{ChainChoice, SpecError};
use crate::{CodegenError, Generated, Report, Scene};

/// Why [`Builder::generate`] or [`Builder::emit_to`] failed. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The scene or URDF file cannot be read or is invalid (file, line, element, attribute).
    #[error(transparent)]
    Scene(#[from] SpecError),
    /// The scene is valid but cannot be turned into the kernels asked for (an unknown kernel,
    /// fused multiply-add in a no_std module, values that overflow, …).
    #[error("{file}: {source}")]
    Codegen {
        /// The scene file as given to [`Builder::new`].
        file: String,
        /// The generator's error.
        #[source]
        source: CodegenError,
    },
    /// A builder setting that cannot hold (an empty kernel list, a bad module file name).
    #[error("{file}: bf_codegen::Builder: {message}")]
    Setting {
        /// The scene file as given to [`Builder::new`].
        file: String,
        /// What is wrong.
        message: String,
    },
    /// The module cannot be written.
    #[error("{}: cannot write the generated module: {source}", path.display())]
    Write {
        /// The file that was being written.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
}

/// Generates the kernel module of a robot at build time; see the module documentation.
/// Defaults: the URDF's only chain (or the scene file's), the scene's kernels plus the
/// inverse-dynamics family ([`crate::kernels::with_robot_kernels`], as `ball-finger generate`
/// emits them), `f64`, no fused multiply-add, `std`, file `<scene name>.rs`, and the
/// `cargo::rerun-if-changed` lines of the files read.
#[derive(Debug, Clone)]
pub struct Builder {
    source: PathBuf,
    chain: ChainChoice,
    kernels: Option<Vec<String>>,
    settings: EmitSettings,
    file_name: Option<String>,
    cargo_metadata: bool,
    max_graph_nodes: Option<usize>,
}

/// What [`Builder::emit_to`] wrote.
#[derive(Debug, Clone)]
pub struct Emitted {
    /// The module file.
    pub path: PathBuf,
    /// The scene's name (also the default file stem), its joints and the kernels' costs.
    pub report: Report,
    /// The files the module was generated from (the scene file, and the URDF it names).
    pub inputs: Vec<PathBuf>,
}

impl Builder {
    /// A builder for the robot of `path`: a `.urdf` file, or a TOML scene file (which may take
    /// its robot from a URDF by its `urdf` key and add a ball and contact).
    pub fn new(path: impl AsRef<Path>) -> Self {
        Builder {
            source: path.as_ref().to_path_buf(),
            chain: ChainChoice::default(),
            kernels: None,
            settings: EmitSettings::default(),
            file_name: None,
            cargo_metadata: true,
            max_graph_nodes: None,
        }
    }

    /// The chain's base link; default: the URDF's root link. As `--base`: it stays where the
    /// joints from the root put it (moving ones at q = 0), the root placed by the scene's
    /// `[base]` (the world origin for a `.urdf` file).
    pub fn base(mut self, link: impl Into<String>) -> Self {
        self.chain.base = Some(link.into());
        self
    }

    /// The chain's tip link; default: the leaf of a tree that does not branch.
    pub fn tip(mut self, link: impl Into<String>) -> Self {
        self.chain.tip = Some(link.into());
        self
    }

    /// Exactly these kernels, in this order (names as in docs/kernels.md; the module's
    /// `eval_index_into` numbers them so).
    pub fn kernels<I, S>(mut self, names: I) -> Self
    where
        I: IntoIterator<Item = S>,
        S: Into<String>,
    {
        self.kernels = Some(names.into_iter().map(Into::into).collect());
        self
    }

    /// Float type of arguments, outputs, constants and arithmetic.
    pub fn float(mut self, float: FloatTy) -> Self {
        self.settings.float = float;
        self
    }

    /// Fused multiply-add for every `a*b ± c` (not with [`Builder::no_std`]).
    pub fn fma(mut self, on: bool) -> Self {
        self.settings.fma = on;
        self
    }

    /// A module for a `#![no_std]` crate ([`EmitSettings::no_std`]).
    pub fn no_std(mut self, on: bool) -> Self {
        self.settings.no_std = on;
        self
    }

    /// The module's file name in the output directory (default `<scene name>.rs`).
    pub fn file_name(mut self, name: impl Into<String>) -> Self {
        self.file_name = Some(name.into());
        self
    }

    /// Whether [`Builder::emit_to`] prints `cargo::rerun-if-changed=` for the files it reads
    /// (default true; turn off outside build scripts).
    pub fn cargo_metadata(mut self, on: bool) -> Self {
        self.cargo_metadata = on;
        self
    }

    /// The node limit of the module's expression graph (default: the process's,
    /// [`crate::graph::node_limit`], [`crate::graph::DEFAULT_NODE_LIMIT`] unless set; about
    /// 6 GiB at the generator's peak): a robot whose kernels need more ends with
    /// [`crate::CodegenError::TooLarge`], naming the kernel, instead of exhausting the machine.
    pub fn max_graph_nodes(mut self, nodes: usize) -> Self {
        self.max_graph_nodes = Some(nodes);
        self
    }

    fn file(&self) -> String {
        self.source.display().to_string()
    }

    fn setting(&self, message: String) -> BuildError {
        BuildError::Setting {
            file: self.file(),
            message,
        }
    }

    /// The scene, its self-contained text and the files read.
    fn load(&self) -> Result<(Scene, String, Vec<PathBuf>), BuildError> {
        let (mut scene, text) = Scene::load_with_text(&self.source, &self.chain)?;
        let mut inputs = vec![self.source.clone()];
        let is_urdf = self
            .source
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("urdf"));
        if !is_urdf {
            // The scene text was just read, so a second read fails only in a race; the URDF it
            // names is then simply not listed.
            if let Ok(raw) = std::fs::read_to_string(&self.source) {
                let dir = self.source.parent().unwrap_or(Path::new(""));
                inputs.extend(crate::spec::urdf_path(&raw, dir));
            }
        }
        match &self.kernels {
            Some(k) if k.is_empty() => {
                return Err(self.setting("the kernel list is empty".into()));
            }
            Some(k) => scene.kernels = k.clone(),
            None => scene = crate::kernels::with_robot_kernels(&scene),
        }
        Ok((scene, text, inputs))
    }

    /// Generates the module (code and report) without writing it.
    pub fn generate(&self) -> Result<Generated, BuildError> {
        let (scene, text, _) = self.load()?;
        self.generate_scene(&scene, &text)
    }

    fn generate_scene(&self, scene: &Scene, text: &str) -> Result<Generated, BuildError> {
        let limit = self
            .max_graph_nodes
            .unwrap_or_else(crate::graph::node_limit);
        let split = crate::emit::ModuleSplit::Auto;
        crate::generate_bounded(scene, text, &self.settings, split, limit).map_err(|source| {
            BuildError::Codegen {
                file: self.file(),
                source,
            }
        })
    }

    /// Generates the module and writes it to `out_dir` (usually `OUT_DIR`) unless the file
    /// there already holds the same text (so Cargo does not recompile the including crate),
    /// through a temporary file and a rename, so a reader never sees half a module.
    pub fn emit_to(&self, out_dir: impl AsRef<Path>) -> Result<Emitted, BuildError> {
        let (scene, text, inputs) = self.load()?;
        if self.cargo_metadata {
            for f in &inputs {
                println!("cargo::rerun-if-changed={}", f.display());
            }
        }
        let name = match &self.file_name {
            Some(n) => {
                if n.is_empty() || n.contains(['/', '\\']) || !n.ends_with(".rs") {
                    return Err(self.setting(format!(
                        "file_name {n:?} must be a plain file name ending in `.rs`"
                    )));
                }
                n.clone()
            }
            None => format!("{}.rs", scene.name),
        };
        let generated = self.generate_scene(&scene, &text)?;
        let path = out_dir.as_ref().join(name);
        write_if_changed(&path, &generated.code)?;
        Ok(Emitted {
            path,
            report: generated.report,
            inputs,
        })
    }
}

fn write_if_changed(path: &Path, text: &str) -> Result<(), BuildError> {
    if std::fs::read(path).ok().as_deref() == Some(text.as_bytes()) {
        return Ok(());
    }
    let err = |source| BuildError::Write {
        path: path.to_path_buf(),
        source,
    };
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    std::fs::write(&tmp, text).map_err(err)?;
    std::fs::rename(&tmp, path).map_err(err)
}
