//! Kernels for any scene file: the compiled kernels of `bf_generated::SCENE_KERNELS` when the
//! scene is one that was compiled in (possibly with other runtime-parameter values), otherwise
//! kernels evaluated at run time by bf-codegen's interpreter on the same expression graphs
//! (`mass_cqd_g` eq. 22a/24, `potential` eq. 22b, `contact` eq. 2–13, `contact_smooth`
//! eq. 58–59). The interpreter runs in `f64` with the emitted kernels' own
//! sine–cosine (`bf_codegen::trig`), so its arithmetic is that of the emitted f64 kernels, so both paths give the same numbers for
//! the same scene; the interpreted path is only slower.
//!
//! - [`compiled_match`]: the compiled entry a parsed scene is equal to, ignoring what does not
//!   enter the model kernels (description, link names, joint and torque limits, the kernel and
//!   node-kernel lists) and the values of the compiled scene's runtime parameters, which become
//!   the parameter vector `p`. A scene named like a compiled one with any other difference
//!   (a link length, a mass, the ball) does not match.
//! - [`compiled_kernels_match`]: the same, also ignoring the physical parameters the model
//!   applies outside its kernels (ball mass and inertia, friction, damping): what
//!   [`contact_kernels_n`] runs on, the compiled kernels carrying the scene's own parameters
//!   ([`CompiledKernels::with_physical_params`]), so that a heavier ball, less friction or more
//!   damping (a perturbed plant) runs compiled.
//! - [`contact_kernels_n`]: a boxed [`Kernels<N>`] for a scene with `N` joints, a ball and a
//!   contact (any N: the compiled registry emits the contact kernels of every scene with a
//!   ball, and the interpreter needs no build), and the [`KernelSource`] it runs on;
//!   [`contact_kernels`] is the 3-joint case. Both paths write the contact outputs in
//!   bf-codegen's `CONTACT_FIELDS` order (J_c row-major 3 × N), decoded by one layout.
//! - [`CompiledKernels::named`], [`compiled_contact_scenes`], [`contact_scene_id`]: the
//!   compiled 3-joint contact scenes by [`SceneId`], the one lookup by name.
//! - [`set_parameters`]: `name = value` assignments to a scene's runtime parameters (the CLI's
//!   `--param`), applied to the parsed scene so that every consumer (model, optimiser, `eval`)
//!   sees the same values.

use std::fmt;

use bf_codegen::interp::Tape;
use bf_codegen::kernels::{CONTACT_FIELDS, Dim, build_kernel};
use bf_codegen::spec::{Angle, InertiaSpec, Scene, SceneId};
use bf_generated::{ContactFn, MassCqdGFn, PotentialFn};

use crate::kernels::{ContactVariant, Kernels};
use crate::{ContactGeometry, ModelError, Params, Result, Shared};

/// Which kernels a model runs on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KernelSource {
    /// The kernels compiled into bf-generated at build time.
    Compiled,
    /// bf-codegen's interpreter on the scene's expression graphs, built at run time.
    Interpreted,
}

impl KernelSource {
    /// `"compiled"` or `"interpreted"` (the word the CLI prints and writes).
    pub fn name(self) -> &'static str {
        match self {
            KernelSource::Compiled => "compiled",
            KernelSource::Interpreted => "interpreted",
        }
    }
}

impl fmt::Display for KernelSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A boxed kernel set of any contact scene with `N` joints (default 3).
pub type DynKernels<const N: usize = 3> = Box<dyn Kernels<N> + Send + Sync>;

/// [`ModelError::Thread`] of the scene `scene`.
pub(crate) fn thread_err(scene: &str, e: std::io::Error) -> ModelError {
    ModelError::Thread {
        scene: scene.to_string(),
        source: Shared::new(e),
    }
}

fn scene_err(scene: &str, message: impl Into<String>) -> ModelError {
    ModelError::Scene {
        scene: scene.to_string(),
        message: message.into(),
    }
}

/// The scene with everything that does not enter the model kernels cleared and inertias as
/// full tensors (a diagonal or a default inertia equals the same tensor written out).
fn kernel_relevant(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    if let Some(b) = &mut s.ball {
        b.inertia = Some(InertiaSpec::Full(b.inertia_matrix()));
    }
    s.description = None;
    s.kernels.clear();
    s.ocp_kernels = None;
    for l in &mut s.links {
        l.name = None;
        l.q_min = None;
        l.q_max = None;
        l.tau_max = None;
        l.inertia = InertiaSpec::Full(l.inertia_matrix());
    }
    s
}

/// [`kernel_relevant`] without what the model applies outside its kernels ([`Params`]): the
/// ball's mass and inertia, and the friction and damping constants. The kernels read the
/// finger, the gravity and the contact geometry (the ball's radius and centre) only.
fn kernel_inputs(scene: &Scene) -> Scene {
    let mut s = kernel_relevant(scene);
    if let Some(b) = &mut s.ball {
        b.mass = 0.0;
        b.inertia = None;
        b.nonphysical_inertia = None;
    }
    s.friction = None;
    s
}

/// The compiled scene `scene` is equal to (see the module docs) and the parameter vector `p`
/// (the scene's values of the compiled scene's runtime parameters, in `PARAM_NAMES` order).
pub fn compiled_match(scene: &Scene) -> Option<(&'static bf_generated::SceneKernels, Vec<f64>)> {
    match_by(scene, kernel_relevant)
}

/// The compiled scene whose kernels compute `scene`'s kernel functions, and the parameter
/// vector `p` as for [`compiled_match`]: the scene may also differ from it in the physical
/// parameters that the model applies outside its kernels (the ball's mass and inertia,
/// friction and damping), which a model on these kernels must then take from `scene`
/// ([`CompiledKernels::with_physical_params`], as [`contact_kernels_n`] does).
pub fn compiled_kernels_match(
    scene: &Scene,
) -> Option<(&'static bf_generated::SceneKernels, Vec<f64>)> {
    match_by(scene, kernel_inputs)
}

/// The compiled entry of `scene`'s name, if `relevant` of the scene with the compiled runtime
/// parameters' values equals `relevant` of the compiled scene, and the scene's values of those
/// parameters.
fn match_by(
    scene: &Scene,
    relevant: fn(&Scene) -> Scene,
) -> Option<(&'static bf_generated::SceneKernels, Vec<f64>)> {
    let entry = bf_generated::scene(&scene.name)?;
    let compiled = Scene::from_toml_str(entry.toml, entry.name).ok()?;
    let mut p = Vec::with_capacity(entry.param_names.len());
    let mut mine = scene.clone();
    // A default ball inertia follows the radius and mass set below, as it follows the
    // compiled kernels' runtime values (`Constants::with_runtime_parameters`).
    mine.runtime_parameters = compiled.runtime_parameters.clone();
    for (name, &default) in entry.param_names.iter().zip(entry.param_defaults) {
        p.push(scene.constant(name)?);
        set_constant(&mut mine, name, default).ok()?;
    }
    (relevant(&mine) == relevant(&compiled)).then_some((entry, p))
}

/// Sets the runtime parameters `assignments` (name, value) of the scene `out`. Every name must
/// be one of the scene's `runtime_parameters` and every value finite; the error names the
/// parameter and lists the valid names. The scene with each value set passes the scene file's
/// validation (`Scene::validate`: masses and radii > 0, inertias positive definite, the scale
/// floor), the error naming the parameter, its value and the failed rule; on any error `out`
/// is unchanged. A ball whose inertia is the default (2/5) m r² has that of the new radius and
/// mass, as a scene file with those values would (and as [`bf_scene::Constants`] gives the
/// compiled kernels' runtime `ball.radius`).
pub fn set_parameters(out: &mut Scene, assignments: &[(String, f64)]) -> Result<()> {
    // Applied to a copy, so a refused value leaves `out` as it was.
    let mut next = out.clone();
    let scene = &mut next;
    for (name, value) in assignments {
        if !scene.is_runtime(name) {
            let valid = if scene.runtime_parameters.is_empty() {
                "the scene has no runtime parameters (list them in `runtime_parameters`)".into()
            } else {
                format!("valid names: {}", scene.runtime_parameters.join(", "))
            };
            return Err(scene_err(
                &scene.name,
                format!("`{name}` is not a runtime parameter of the scene; {valid}"),
            ));
        }
        if !value.is_finite() {
            return Err(scene_err(
                &scene.name,
                format!("runtime parameter `{name}` must be finite (got {value})"),
            ));
        }
        set_constant(scene, name, *value)?;
        scene.validate(&scene.name).map_err(|e| {
            let rule = match &e {
                bf_scene::SpecError::At { path, message, .. } => format!("{path}: {message}"),
                other => other.to_string(),
            };
            scene_err(
                &scene.name,
                format!("runtime parameter `{name}` = {value:?} is invalid: {rule}"),
            )
        })?;
    }
    *out = next;
    Ok(())
}

/// Sets one registry constant (`Scene::constants` naming) of `scene` to `value`.
fn set_constant(scene: &mut Scene, name: &str, value: f64) -> Result<()> {
    let unknown = || scene_err(&scene.name, format!("unknown scene constant `{name}`"));
    let (xyz, sym) = (bf_scene::axis_index, bf_scene::inertia_index);
    let set_sym = |m: [[f64; 3]; 3], (i, j): (usize, usize)| {
        let mut m = m;
        m[i][j] = value;
        m[j][i] = value;
        InertiaSpec::Full(m)
    };
    let parts: Vec<&str> = name.split('.').collect();
    match parts.as_slice() {
        ["gravity", c] => scene.gravity[xyz(c).ok_or_else(unknown)?] = value,
        ["base", "translation", c] => {
            let i = xyz(c).ok_or_else(unknown)?;
            let mut t = scene.base.translation();
            t[i] = value;
            scene.base.translation = Some(t);
        }
        ["tool", "translation", c] => {
            let i = xyz(c).ok_or_else(unknown)?;
            let err = unknown();
            let tool = scene.tool.as_mut().ok_or(err)?;
            let mut t = tool.translation();
            t[i] = value;
            tool.translation = Some(t);
        }
        [link, rest @ ..] if link.starts_with("link") => {
            let k: usize = link["link".len()..].parse().map_err(|_| unknown())?;
            let err = unknown();
            let l = k
                .checked_sub(1)
                .and_then(|i| scene.links.get_mut(i))
                .ok_or(err)?;
            match rest {
                ["a"] => l.a = value,
                ["d"] => l.d = value,
                ["alpha"] => l.alpha = Angle::Radians(value),
                ["offset"] => l.offset = Some(Angle::Radians(value)),
                ["mass"] => l.mass = value,
                ["com", c] => l.com[xyz(c).ok_or_else(unknown)?] = value,
                ["inertia", c] => {
                    let ij = sym(c).ok_or_else(unknown)?;
                    l.inertia = set_sym(l.inertia_matrix(), ij);
                }
                _ => return Err(unknown()),
            }
        }
        ["ball", rest @ ..] => {
            let err = unknown();
            let b = scene.ball.as_mut().ok_or(err)?;
            match rest {
                ["radius"] => b.radius = value,
                ["mass"] => b.mass = value,
                ["center", c] => b.center[xyz(c).ok_or_else(unknown)?] = value,
                ["inertia", c] => {
                    let ij = sym(c).ok_or_else(unknown)?;
                    b.inertia = Some(set_sym(b.inertia_matrix(), ij));
                }
                _ => return Err(unknown()),
            }
        }
        ["friction", c] => {
            let err = unknown();
            let f = scene.friction.as_mut().ok_or(err)?;
            match *c {
                "mu_s" => f.mu_s = value,
                "mu_k" => f.mu_k = value,
                "mu_v" => f.mu_v = value,
                "socket_damping" => f.socket_damping = value,
                _ => return Err(unknown()),
            }
        }
        _ => return Err(unknown()),
    }
    Ok(())
}

/// Errors unless `scene` can carry the contact model: a ball, a contact and friction (any
/// number of joints; the error names the joints for orientation).
pub fn check_contact_scene(scene: &Scene) -> Result<()> {
    let mut missing = Vec::new();
    if scene.ball.is_none() {
        missing.push("no [ball]");
    }
    if scene.contact.is_none() {
        missing.push("no [contact]");
    }
    if scene.friction.is_none() {
        missing.push("no [friction]");
    }
    if missing.is_empty() {
        Ok(())
    } else {
        Err(scene_err(
            &scene.name,
            format!(
                "not a finger-and-ball contact scene ({} joints): {}",
                scene.links.len(),
                missing.join(", ")
            ),
        ))
    }
}

/// Error unless `scene` has `N` joints (the caller's model type is for N joints).
fn check_joints<const N: usize>(scene: &Scene) -> Result<()> {
    if scene.links.len() == N {
        Ok(())
    } else {
        Err(scene_err(
            &scene.name,
            format!(
                "the scene has {} joints, these contact kernels are for {N}",
                scene.links.len()
            ),
        ))
    }
}

/// The kernels of a 3-joint contact scene ([`contact_kernels_n`] with N = 3).
pub fn contact_kernels(scene: &Scene) -> Result<(DynKernels, KernelSource)> {
    contact_kernels_n::<3>(scene)
}

/// The kernels of a contact scene with `N` joints: compiled when [`compiled_kernels_match`]
/// finds the scene (with its runtime-parameter values, and its own ball mass, friction and
/// damping as the kernels' physical parameters), interpreted otherwise. Errors unless the
/// scene has a ball, a contact, friction and `N` joints.
pub fn contact_kernels_n<const N: usize>(scene: &Scene) -> Result<(DynKernels<N>, KernelSource)> {
    check_contact_scene(scene)?;
    check_joints::<N>(scene)?;
    if let Some((entry, p)) = compiled_kernels_match(scene)
        && let Some(k) = CompiledKernels::<N>::from_entry(entry, p)?
    {
        let k = k.with_physical_params(Params::from_scene(scene)?);
        return Ok((Box::new(k), KernelSource::Compiled));
    }
    Ok((
        Box::new(InterpretedKernels::<N>::for_scene(scene)?),
        KernelSource::Interpreted,
    ))
}

/// A compiled contact scene of the registry with `N` joints (default 3) and a
/// runtime-parameter vector.
#[derive(Debug, Clone)]
pub struct CompiledKernels<const N: usize = 3> {
    entry: &'static bf_generated::SceneKernels,
    mass_cqd_g: MassCqdGFn,
    potential: PotentialFn,
    contact: ContactFn,
    p: Vec<f64>,
    layout: ContactLayout,
    /// The physical parameters of the scene these kernels serve, where it is not the compiled
    /// scene itself ([`CompiledKernels::with_physical_params`]); `None`: the compiled scene's
    /// (with the runtime parameters).
    params: Option<Params>,
}

impl CompiledKernels<3> {
    /// The compiled 3-joint contact scene `id` with its default runtime parameters (the one
    /// lookup of a compiled scene's kernels by name); an error names the compiled contact
    /// scenes if there is none of that name.
    pub fn named(id: &SceneId) -> Result<Self> {
        let found = bf_generated::scene(id.as_str())
            .map(|e| Self::from_entry(e, e.param_defaults.to_vec()))
            .transpose()?
            .flatten();
        found.ok_or_else(|| {
            let available: Vec<String> = compiled_contact_scenes()
                .iter()
                .map(SceneId::to_string)
                .collect();
            scene_err(
                id.as_str(),
                format!("unknown contact scene; available: {}", available.join(", ")),
            )
        })
    }
}

impl<const N: usize> CompiledKernels<N> {
    /// Kernels of `entry` with parameters `p` (length NP, finite); `None` if the entry is not
    /// a contact scene with `N` joints, `mass_cqd_g`, `potential` and the contact kernels.
    pub fn from_entry(
        entry: &'static bf_generated::SceneKernels,
        p: Vec<f64>,
    ) -> Result<Option<Self>> {
        if p.len() != entry.param_names.len() {
            return Err(ModelError::Scene {
                scene: entry.name.to_string(),
                message: format!(
                    "expected {} runtime parameters, got {}",
                    entry.param_names.len(),
                    p.len()
                ),
            });
        }
        if !p.iter().all(|v| v.is_finite()) {
            return Err(ModelError::NonFinite {
                what: "kernel parameters",
            });
        }
        let (Some(mass_cqd_g), Some(potential), Some(contact)) =
            (entry.mass_cqd_g, entry.potential, entry.contact)
        else {
            return Ok(None);
        };
        if entry.nq != N {
            return Ok(None);
        }
        Ok(Some(CompiledKernels {
            entry,
            mass_cqd_g,
            potential,
            contact,
            p,
            layout: ContactLayout::new(N)?,
            params: None,
        }))
    }

    /// These kernels for a scene whose physical parameters outside the kernels (the ball's
    /// mass and inertia, friction, damping) are `params` ([`compiled_kernels_match`]): what
    /// [`Kernels::physical_params`] then gives a model built on them.
    pub fn with_physical_params(mut self, params: Params) -> Self {
        self.params = Some(params);
        self
    }
}

/// The compiled 3-joint contact scenes (registry order: `scenes/*.toml` order): those
/// [`CompiledKernels::named`] finds.
pub fn compiled_contact_scenes() -> Vec<SceneId> {
    bf_generated::SCENE_KERNELS
        .iter()
        .filter(|e| {
            e.nq == 3 && e.contact.is_some() && e.mass_cqd_g.is_some() && e.potential.is_some()
        })
        .map(|e| SceneId::from_static(e.name))
        .collect()
}

/// The compiled contact scene named `text` (user input, e.g. a command-line value); the error
/// names `text` and lists the compiled contact scenes.
pub fn contact_scene_id(text: &str) -> Result<SceneId> {
    SceneId::parse_among(text, &compiled_contact_scenes()).map_err(ModelError::NotCompiled)
}

/// Flat outputs longer than this go through a heap buffer (N > 35 joints).
const STACK_OUTPUTS: usize = 128;

impl<const N: usize> Kernels<N> for CompiledKernels<N> {
    fn scene_name(&self) -> &str {
        self.entry.name
    }
    fn scene_toml(&self) -> &str {
        self.entry.toml
    }
    fn param_names(&self) -> &[&str] {
        self.entry.param_names
    }
    fn param_values(&self) -> &[f64] {
        &self.p
    }
    fn physical_params(&self) -> Option<Params> {
        self.params
    }
    fn mass_cqd_g(&self, q: &[f64; N], qd: &[f64; N]) -> ([[f64; N]; N], [f64; N]) {
        let mut m = [[0.0; N]; N];
        let mut c = [0.0; N];
        (self.mass_cqd_g)(q, qd, &self.p, m.as_flattened_mut(), &mut c);
        (m, c)
    }
    fn potential(&self, q: &[f64; N]) -> f64 {
        (self.potential)(q, &self.p)
    }
    fn contact(
        &self,
        q: &[f64; N],
        qd: &[f64; N],
        omega: &[f64; 3],
        variant: ContactVariant,
    ) -> ContactGeometry<N> {
        let eps = variant.eps();
        let len = self.layout.len;
        if len <= STACK_OUTPUTS {
            let mut v = [0.0; STACK_OUTPUTS];
            (self.contact)(q, qd, omega, eps, &self.p, &mut v[..len]);
            self.layout.geometry(&v[..len])
        } else {
            let mut v = vec![0.0; len];
            (self.contact)(q, qd, omega, eps, &self.p, &mut v);
            self.layout.geometry(&v)
        }
    }
}

/// Where the fields of the model's [`ContactGeometry`] sit in the flat outputs of the contact
/// kernels of a scene with `nq` joints: bf-codegen's `CONTACT_FIELDS` order (the emitted
/// `Contact` struct's layout), which both the compiled registry wrappers and the interpreter
/// tapes write.
#[derive(Debug, Clone, Copy)]
struct ContactLayout {
    /// Offsets of alpha, sat_alpha, p_c, r_c, h, n, j_c, v_c, delta_v, h_dot, rc_dot,
    /// jc_dot_qd.
    offsets: [usize; 12],
    /// Number of outputs (25 + 3 nq).
    len: usize,
}

impl ContactLayout {
    fn new(nq: usize) -> Result<Self> {
        let fields: [(&str, usize); 12] = [
            ("alpha", 1),
            ("sat_alpha", 1),
            ("p_c", 3),
            ("r_c", 3),
            ("h", 1),
            ("n", 3),
            ("j_c", 3 * nq),
            ("v_c", 3),
            ("delta_v", 3),
            ("h_dot", 1),
            ("rc_dot", 3),
            ("jc_dot_qd", 3),
        ];
        let mut layout = Vec::with_capacity(CONTACT_FIELDS.len());
        let mut off = 0;
        for (name, dims, _) in CONTACT_FIELDS {
            let len: usize = dims
                .iter()
                .map(|d| match d {
                    Dim::Nq => nq,
                    Dim::Lit(n) => *n,
                })
                .product();
            layout.push((*name, off, len));
            off += len;
        }
        let mut offsets = [0; 12];
        for (slot, (name, len)) in offsets.iter_mut().zip(fields) {
            match layout.iter().find(|f| f.0 == name) {
                Some(&(_, at, n)) if n == len => *slot = at,
                _ => {
                    return Err(scene_err(
                        "-",
                        format!(
                            "bf-codegen's contact layout has no field `{name}` of {len} values"
                        ),
                    ));
                }
            }
        }
        Ok(ContactLayout { offsets, len: off })
    }

    /// The geometry from flat outputs `v` (J_c row-major 3 × N).
    fn geometry<const N: usize>(&self, v: &[f64]) -> ContactGeometry<N> {
        let o = &self.offsets;
        let a3 = |k: usize| [v[o[k]], v[o[k] + 1], v[o[k] + 2]];
        let j = o[6];
        let j_c: [[f64; N]; 3] = std::array::from_fn(|r| std::array::from_fn(|c| v[j + r * N + c]));
        ContactGeometry::from_arrays(
            v[o[0]],
            v[o[1]],
            &a3(2),
            &a3(3),
            v[o[4]],
            &a3(5),
            &j_c,
            &a3(7),
            &a3(8),
            v[o[9]],
            &a3(10),
            &a3(11),
        )
    }
}

/// Interpreter tapes of some of a scene's kernels, built from the generator's kernel
/// definitions (the graphs the compiled kernels are emitted from).
pub(crate) struct InterpretedTapes<const N: usize> {
    /// One tape per requested kernel, in the requested order.
    pub tapes: [Tape; N],
    /// Where q, q̇, ω, ε and the runtime parameters sit in a tape's variable vector.
    pub layout: bf_codegen::robot::Layout,
    /// The variable vector with the runtime parameters at the scene's values (q, q̇, ω, ε are
    /// set per call).
    pub base_vars: Vec<f64>,
}

/// The tapes of `kernels` of `scene` (see [`InterpretedTapes`]).
pub(crate) fn interpreted_tapes<const N: usize>(
    scene: &Scene,
    kernels: [&str; N],
) -> Result<InterpretedTapes<N>> {
    let codegen = |e: bf_codegen::CodegenError| ModelError::Graphs {
        scene: scene.name.clone(),
        source: Shared::new(e),
    };
    let mut m = bf_codegen::SymbolicRobot::new(scene).map_err(codegen)?;
    let mut tapes = Vec::with_capacity(N);
    for kernel in kernels {
        let def = build_kernel(&mut m, kernel).map_err(codegen)?;
        let ids: Vec<_> = def.output_ids();
        tapes.push(Tape::new(&m.g, &ids));
    }
    let tapes: [Tape; N] = tapes
        .try_into()
        .map_err(|_| scene_err(&scene.name, "internal: one tape per kernel"))?;
    let mut base_vars = vec![0.0; m.layout.n_vars()];
    for (i, p) in m.params.iter().enumerate() {
        base_vars[m.layout.param(i) as usize] = p.1;
    }
    Ok(InterpretedTapes {
        tapes,
        layout: m.layout,
        base_vars,
    })
}

/// Kernels of a contact scene with `N` joints (default 3) evaluated by the interpreter on the
/// tapes of the generator's kernel definitions (the graphs the compiled kernels are emitted
/// from).
#[derive(Debug, Clone)]
pub struct InterpretedKernels<const N: usize = 3> {
    name: String,
    params: Params,
    mass_cqd_g: Tape,
    potential: Tape,
    exact: Tape,
    smooth: Tape,
    layout: ContactLayout,
    tape_layout: bf_codegen::robot::Layout,
    /// The variable vector with the runtime parameters filled in (q, q̇, ω, ε are set per call).
    base_vars: Vec<f64>,
}

impl InterpretedKernels<3> {
    /// The kernels of a 3-joint contact scene ([`InterpretedKernels::for_scene`]).
    pub fn new(scene: &Scene) -> Result<Self> {
        Self::for_scene(scene)
    }
}

impl<const N: usize> InterpretedKernels<N> {
    /// Builds the tapes of `scene` (`N` joints, ball, contact; runtime parameters at the
    /// scene's values). Runs on a helper thread with a large stack: building the graphs of a
    /// scene with runtime parameters recurses deeply in bf-codegen.
    pub fn for_scene(scene: &Scene) -> Result<Self> {
        check_contact_scene(scene)?;
        check_joints::<N>(scene)?;
        let params = Params::from_scene(scene)?;
        std::thread::scope(|s| {
            std::thread::Builder::new()
                .stack_size(256 << 20)
                .spawn_scoped(s, || Self::build(scene, params))
                .map_err(|e| thread_err(&scene.name, e))?
                .join()
                .map_err(|_| scene_err(&scene.name, "building the kernel graphs panicked"))?
        })
    }

    fn build(scene: &Scene, params: Params) -> Result<Self> {
        let InterpretedTapes {
            tapes: [mass_cqd_g, potential, exact, smooth],
            layout,
            base_vars,
        } = interpreted_tapes(
            scene,
            ["mass_cqd_g", "potential", "contact", "contact_smooth"],
        )?;
        Ok(InterpretedKernels {
            name: scene.name.clone(),
            params,
            mass_cqd_g,
            potential,
            exact,
            smooth,
            layout: ContactLayout::new(N)?,
            tape_layout: layout,
            base_vars,
        })
    }

    /// `f` of the outputs of `tape` at (q, q̇, ω, ε), evaluated in this thread's
    /// [`TAPE_BUFFERS`]: no allocation per call once they have grown. `f` must not evaluate a
    /// tape itself (the buffers are borrowed while it runs; none of the callers below does).
    fn eval<R>(
        &self,
        tape: &Tape,
        (q, qd, w, eps): (&[f64; N], &[f64; N], &[f64; 3], f64),
        f: impl FnOnce(&[f64]) -> R,
    ) -> R {
        TAPE_BUFFERS.with(|b| {
            let mut b = b.borrow_mut();
            let TapeBuffers {
                vars,
                values,
                outputs,
            } = &mut *b;
            vars.clear();
            vars.extend_from_slice(&self.base_vars);
            let l = &self.tape_layout;
            for i in 0..N {
                vars[l.q(i) as usize] = q[i];
                vars[l.qd(i) as usize] = qd[i];
            }
            for i in 0..3 {
                vars[l.omega(i) as usize] = w[i];
            }
            vars[l.eps() as usize] = eps;
            outputs.clear();
            outputs.resize(tape.n_outputs(), 0.0);
            tape.eval_into(vars, values, outputs);
            f(outputs)
        })
    }
}

/// The buffers of one thread's interpreted kernel calls: the variable vector, the tape's
/// values and its outputs.
#[derive(Default)]
struct TapeBuffers {
    vars: Vec<f64>,
    values: Vec<f64>,
    outputs: Vec<f64>,
}

thread_local! {
    /// Per thread, so that [`InterpretedKernels`] stays `Sync` (multi-start runs share it
    /// across threads) and a call allocates nothing once the buffers have grown.
    static TAPE_BUFFERS: std::cell::RefCell<TapeBuffers> = std::cell::RefCell::default();
}

impl<const N: usize> Kernels<N> for InterpretedKernels<N> {
    fn scene_name(&self) -> &str {
        &self.name
    }
    /// Empty: the kernels were built from a parsed scene, whose parameters
    /// [`Kernels::physical_params`] gives.
    fn scene_toml(&self) -> &str {
        ""
    }
    fn param_names(&self) -> &[&str] {
        &[]
    }
    fn param_values(&self) -> &[f64] {
        &[]
    }
    fn physical_params(&self) -> Option<Params> {
        Some(self.params)
    }
    fn mass_cqd_g(&self, q: &[f64; N], qd: &[f64; N]) -> ([[f64; N]; N], [f64; N]) {
        self.eval(&self.mass_cqd_g, (q, qd, &[0.0; 3], 0.0), |v| {
            let m = std::array::from_fn(|i| std::array::from_fn(|j| v[i * N + j]));
            (m, std::array::from_fn(|i| v[N * N + i]))
        })
    }
    fn potential(&self, q: &[f64; N]) -> f64 {
        self.eval(&self.potential, (q, &[0.0; N], &[0.0; 3], 0.0), |v| v[0])
    }
    fn contact(
        &self,
        q: &[f64; N],
        qd: &[f64; N],
        omega: &[f64; 3],
        variant: ContactVariant,
    ) -> ContactGeometry<N> {
        let geometry = |v: &[f64]| self.layout.geometry(v);
        match variant {
            ContactVariant::Exact => self.eval(&self.exact, (q, qd, omega, 0.0), geometry),
            ContactVariant::Smooth(e) => self.eval(&self.smooth, (q, qd, omega, e), geometry),
        }
    }
}
