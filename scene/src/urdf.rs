//! URDF import: the serial chain base → tip of a URDF robot as placement-form links
//! ([`LinkSpec`] with `origin` and `axis`), the same description the DH readers produce.
//!
//! Semantics (as Pinocchio's `buildReducedModel` with every joint off the chain locked at 0):
//! * the root link is the world frame of the URDF; the base link (the root by default) sits
//!   where the joints from the root down to it put it with their moving joints at q = 0, the
//!   product of their origins ([`UrdfChain::base`]): a scene uses that pose as the chain's
//!   base transform, after its own `[base]` (which places the root in the world), so the
//!   choice of base link changes which joints move, never where the robot is or which way
//!   gravity pulls;
//! * the moving joints (revolute, continuous, prismatic) on the chain from the base link to the
//!   tip link are the model's joints, in chain order; continuous joints are revolute joints
//!   without limits;
//! * fixed joints are merged: the placement of model joint j is the product of the joint
//!   origins (xyz, then rpy = R_z(y) R_y(p) R_x(r)) from the previous moving joint's child link
//!   to joint j's own origin; the transform from the last moving joint to the tip link is the
//!   scene's tool;
//! * every link below a model joint (fixed children, and branches whose joints are locked at
//!   q = 0) is lumped into that joint's link: masses add, the COG is the mass-weighted mean and
//!   the inertia tensors (rotated by the inertial origin's rpy and the link's pose) are moved
//!   to the common COG by the parallel-axis theorem, I = Σ R I_k Rᵀ + m_k (|d_k|² 1 − d_k d_kᵀ)
//!   (the m_i, COG and I_i of paper eq. 22a);
//! * bodies that do not move (fixed to the base before the first moving joint, above the base
//!   link, or on branches off the path from the root to it) are dropped;
//! * an `<inertial>` of mass 0 and a zero inertia (a dummy link) counts as none;
//! * any finite non-zero `<axis>` is normalised, as urdfdom does;
//! * `<visual>`, `<collision>`, meshes, `<transmission>` and `<gazebo>` are ignored.
//!
//! Errors ([`SpecError::Urdf`], a [`UrdfError`]) name the file, line and column, the element
//! and the attribute. A base or tip that names no link is a [`SpecError::UnknownLink`], which
//! the caller blames on whoever named it.

use crate::error::{ChainEnd, UnknownLink, UrdfError};
use crate::{InertiaSpec, JointType, LinkSpec, RotationSpec, SpecError, TransformSpec};

/// A 3 × 3 matrix, row-major.
pub(crate) type M3 = [[f64; 3]; 3];
type V3 = [f64; 3];
/// A rigid transform x ↦ R x + t.
type Pose = (M3, V3);

const I3: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// The serial chain read from a URDF: the model's links (placement form), the tool (the tip
/// link's frame in the last moving link's frame; `None` when the tip is that link) and the
/// names the chain was chosen by.
#[derive(Debug, Clone, PartialEq)]
pub struct UrdfChain {
    /// The `<robot name>`.
    pub robot: String,
    /// The URDF's root link (the link no joint moves).
    pub root_link: String,
    /// The base link, where the chain starts: fixed to the world at [`UrdfChain::base`].
    pub base_link: String,
    /// The tip link (the end of the chain).
    pub tip_link: String,
    /// The base link's pose in the root link's frame: the product of the joint origins from
    /// the root down to the base link, every moving joint on that path at q = 0 (as
    /// Pinocchio's `buildReducedModel` locks them); `None` when that is the identity (the base
    /// link is the root, by default). A scene places the root in the world by its `[base]`,
    /// so the chain's base transform is `[base]` ∘ this.
    pub base: Option<TransformSpec>,
    /// One link per moving joint on the chain, in chain order.
    pub links: Vec<LinkSpec>,
    /// Transform from the last moving joint's frame to the tip link.
    pub tool: Option<TransformSpec>,
    /// The names of the moving joints, in chain order.
    pub joint_names: Vec<String>,
    /// Where each model link's `<link>` element (the moving joint's child) is in the URDF:
    /// (line, column), 1-based, so that errors found on the generated links can name it.
    pub link_positions: Vec<(usize, usize)>,
}

#[derive(Debug, Clone)]
struct Inertial {
    mass: f64,
    /// COG in the link frame.
    com: V3,
    /// Inertia about the COG in link-frame axes.
    inertia: M3,
}

#[derive(Debug, Clone)]
struct Link {
    name: String,
    pos: usize,
    /// `None` for a link without `<inertial>` and for one whose `<inertial>` has mass 0 and a
    /// zero inertia (a dummy link).
    inertial: Option<Inertial>,
    /// Where the `<inertia>` element of `inertial` is, to point at it.
    inertia_pos: usize,
    /// Its `<inertial>` was a massless one, dropped: errors about its missing mass say so.
    massless_inertial: bool,
}

#[derive(Debug, Clone)]
struct Joint {
    name: String,
    pos: usize,
    kind: JointKind,
    parent: usize,
    child: usize,
    origin: (M3, V3),
    axis: V3,
    limit: Option<(f64, f64, f64)>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum JointKind {
    Revolute,
    Continuous,
    Prismatic,
    Fixed,
}

struct Reader<'a> {
    file: &'a str,
    doc: &'a roxmltree::Document<'a>,
}

impl Reader<'_> {
    fn err(&self, pos: usize, element: &str, attribute: &str, message: String) -> SpecError {
        let p = self.doc.text_pos_at(pos);
        SpecError::Urdf(Box::new(UrdfError {
            file: self.file.to_string(),
            line: p.row as usize,
            column: p.col as usize,
            element: element.to_string(),
            attribute: attribute.to_string(),
            message,
        }))
    }

    fn node_err(&self, n: roxmltree::Node, attribute: &str, message: String) -> SpecError {
        let pos = n
            .attribute_node(attribute)
            .map_or(n.range().start, |a| a.range().start);
        self.err(pos, n.tag_name().name(), attribute, message)
    }

    fn attr<'n>(&self, n: roxmltree::Node<'n, 'n>, name: &str) -> Result<&'n str, SpecError> {
        n.attribute(name)
            .ok_or_else(|| self.node_err(n, name, "required attribute is missing".to_string()))
    }

    fn numbers<const K: usize>(
        &self,
        n: roxmltree::Node,
        name: &str,
        default: Option<[f64; K]>,
    ) -> Result<[f64; K], SpecError> {
        let Some(text) = n.attribute(name) else {
            return default.ok_or_else(|| {
                self.node_err(n, name, "required attribute is missing".to_string())
            });
        };
        let parts: Vec<&str> = text.split_whitespace().collect();
        if parts.len() != K {
            return Err(self.node_err(n, name, format!("expected {K} number(s), got {:?}", text)));
        }
        let mut out = [0.0; K];
        for (o, p) in out.iter_mut().zip(&parts) {
            *o = match p.parse::<f64>() {
                Ok(v) if v.is_finite() => v,
                _ => {
                    return Err(self.node_err(
                        n,
                        name,
                        format!("{p:?} is not a finite number (in {text:?})"),
                    ));
                }
            };
        }
        Ok(out)
    }

    /// The child element `tag` of `n`, if any; an error naming the second one if `n` has two
    /// (the URDF allows one: silently taking the first would drop what the author meant).
    fn child<'n>(
        &self,
        n: roxmltree::Node<'n, 'n>,
        tag: &str,
    ) -> Result<Option<roxmltree::Node<'n, 'n>>, SpecError> {
        let mut found = n.children().filter(|c| is_urdf(c, tag));
        let first = found.next();
        if let Some(second) = found.next() {
            return Err(self.err(
                second.range().start,
                tag,
                "",
                format!(
                    "<{}> has a second <{tag}>; the URDF allows one",
                    n.tag_name().name()
                ),
            ));
        }
        Ok(first)
    }

    /// `<origin xyz rpy>` of `n` (identity when absent).
    fn origin(&self, n: roxmltree::Node) -> Result<(M3, V3), SpecError> {
        let Some(o) = self.child(n, "origin")? else {
            return Ok((I3, [0.0; 3]));
        };
        let xyz = self.numbers::<3>(o, "xyz", Some([0.0; 3]))?;
        let rpy = self.numbers::<3>(o, "rpy", Some([0.0; 3]))?;
        Ok((rpy_matrix(rpy), xyz))
    }

    fn link(&self, n: roxmltree::Node) -> Result<Link, SpecError> {
        let name = self.attr(n, "name")?.to_string();
        let mut link = Link {
            name,
            pos: n.range().start,
            inertial: None,
            inertia_pos: n.range().start,
            massless_inertial: false,
        };
        let Some(i) = self.child(n, "inertial")? else {
            return Ok(link);
        };
        let (r, c) = self.origin(i)?;
        let m = self.child(i, "mass")?.ok_or_else(|| {
            self.node_err(i, "mass", "<inertial> has no <mass> element".to_string())
        })?;
        let [mass] = self.numbers::<1>(m, "value", None)?;
        if mass < 0.0 {
            return Err(self.node_err(
                m,
                "value",
                format!("mass must be > 0 (got {mass}), or 0 on a massless link"),
            ));
        }
        let t = self.child(i, "inertia")?.ok_or_else(|| {
            self.node_err(
                i,
                "inertia",
                "<inertial> has no <inertia> element".to_string(),
            )
        })?;
        let mut v = [0.0; 6];
        for (k, a) in ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"]
            .iter()
            .enumerate()
        {
            [v[k]] = self.numbers::<1>(t, a, None)?;
        }
        if mass == 0.0 {
            // Published URDFs mark frames-only links by mass 0 and a zero inertia (urdfdom
            // reads them as bodies of no mass); such a link carries nothing, exactly like one
            // without <inertial>. A zero mass with an inertia is a contradiction, not a dummy.
            if v.iter().any(|&x| x != 0.0) {
                return Err(self.node_err(
                    m,
                    "value",
                    format!(
                        "link {:?}: mass is 0 but its <inertia> is not zero; give the mass, or \
                         zero the inertia too for a massless link (as one without <inertial>)",
                        link.name
                    ),
                ));
            }
            link.massless_inertial = true;
            return Ok(link);
        }
        let local = [[v[0], v[1], v[2]], [v[1], v[3], v[4]], [v[2], v[4], v[5]]];
        link.inertial = Some(Inertial {
            mass,
            com: c,
            inertia: rotate_tensor(&r, &local),
        });
        link.inertia_pos = t.range().start;
        Ok(link)
    }

    fn joint(&self, n: roxmltree::Node, links: &[Link]) -> Result<Joint, SpecError> {
        let name = self.attr(n, "name")?.to_string();
        let ty = self.attr(n, "type")?;
        let kind = match ty {
            "revolute" => JointKind::Revolute,
            "continuous" => JointKind::Continuous,
            "prismatic" => JointKind::Prismatic,
            "fixed" => JointKind::Fixed,
            "floating" | "planar" => {
                return Err(self.node_err(
                    n,
                    "type",
                    format!(
                        "joint {name:?}: type {ty:?} is not supported (a serial chain has \
                         revolute, continuous, prismatic and fixed joints)"
                    ),
                ));
            }
            other => {
                return Err(self.node_err(
                    n,
                    "type",
                    format!(
                        "joint {name:?}: unknown joint type {other:?} (expected revolute, \
                         continuous, prismatic or fixed)"
                    ),
                ));
            }
        };
        let end = |tag: &str| -> Result<usize, SpecError> {
            let e = self.child(n, tag)?.ok_or_else(|| {
                self.node_err(n, tag, format!("joint {name:?} has no <{tag}> element"))
            })?;
            let l = self.attr(e, "link")?;
            links.iter().position(|k| k.name == l).ok_or_else(|| {
                self.node_err(e, "link", format!("joint {name:?}: no <link name={l:?}>"))
            })
        };
        let parent = end("parent")?;
        let child = end("child")?;
        let origin = self.origin(n)?;
        let axis = match self.child(n, "axis")? {
            None => [1.0, 0.0, 0.0],
            Some(a) => {
                let v = self.numbers::<3>(a, "xyz", Some([1.0, 0.0, 0.0]))?;
                match unit_axis(v) {
                    Some(u) => u,
                    // A fixed joint does not use its axis.
                    None if kind == JointKind::Fixed => v,
                    None => {
                        return Err(self.node_err(
                            a,
                            "xyz",
                            format!("joint {name:?}: the axis must not be zero (got {v:?})"),
                        ));
                    }
                }
            }
        };
        let limit = match (kind, self.child(n, "limit")?) {
            (JointKind::Revolute | JointKind::Prismatic, Some(l)) => {
                let [lo] = self.numbers::<1>(l, "lower", Some([0.0]))?;
                let [hi] = self.numbers::<1>(l, "upper", Some([0.0]))?;
                let [effort] = self.numbers::<1>(l, "effort", Some([0.0]))?;
                if lo > hi {
                    return Err(self.node_err(
                        l,
                        "lower",
                        format!("joint {name:?}: lower = {lo} > upper = {hi}"),
                    ));
                }
                Some((lo, hi, effort))
            }
            // A continuous joint's <limit> has no range (URDF ignores lower/upper there), but
            // its effort bounds the torque as a revolute joint's does.
            (JointKind::Continuous, Some(l)) => {
                let [effort] = self.numbers::<1>(l, "effort", Some([0.0]))?;
                Some((0.0, 0.0, effort))
            }
            _ => None,
        };
        Ok(Joint {
            name,
            pos: n.range().start,
            kind,
            parent,
            child,
            origin,
            axis,
            limit,
        })
    }
}

/// The unit vector along the finite `v`, `None` if `v` is zero. As urdfdom, any non-zero axis
/// gives its direction: where its squares would overflow (1e200) or underflow (1e-200), `v`
/// is divided by its largest |component| before the norm is taken.
fn unit_axis(v: V3) -> Option<V3> {
    let scale = v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    if scale == 0.0 {
        return None;
    }
    // Where the squares neither overflow nor underflow, the plain norm: the direction a URDF
    // of ordinary axes has always given, bit for bit (generated code stays the same).
    let norm = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if (1e-150..=1e150).contains(&scale) && norm.is_normal() {
        return Some(v.map(|x| x / norm));
    }
    let w = v.map(|x| x / scale);
    let norm = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
    Some(w.map(|x| x / norm))
}

/// R = R_z(yaw) R_y(pitch) R_x(roll), the URDF convention.
pub fn rpy_matrix([r, p, y]: V3) -> M3 {
    let (sr, cr) = libm::sincos(r);
    let (sp, cp) = libm::sincos(p);
    let (sy, cy) = libm::sincos(y);
    [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
}

pub(crate) fn mat_mul(a: &M3, b: &M3) -> M3 {
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    out
}

pub(crate) fn mat_vec(a: &M3, v: V3) -> V3 {
    [0, 1, 2].map(|i| a[i][0] * v[0] + a[i][1] * v[1] + a[i][2] * v[2])
}

/// R I Rᵀ.
fn rotate_tensor(r: &M3, i: &M3) -> M3 {
    let ri = mat_mul(r, i);
    let mut out = [[0.0; 3]; 3];
    for (a, row) in out.iter_mut().enumerate() {
        for (b, x) in row.iter_mut().enumerate() {
            *x = (0..3).map(|k| ri[a][k] * r[b][k]).sum();
        }
    }
    out
}

/// a ∘ b for poses x ↦ R x + t.
pub(crate) fn compose(a: &Pose, b: &Pose) -> Pose {
    let rt = mat_vec(&a.0, b.1);
    (mat_mul(&a.0, &b.0), [0, 1, 2].map(|k| rt[k] + a.1[k]))
}

/// Adds body `b` (in the owner's frame) to the lumped inertia `acc`, both about their own COG.
fn lump(acc: Option<Inertial>, b: Inertial) -> Inertial {
    let Some(a) = acc else { return b };
    let m = a.mass + b.mass;
    let c = [0, 1, 2].map(|k| (a.mass * a.com[k] + b.mass * b.com[k]) / m);
    let shift = |x: &Inertial| {
        let d = [0, 1, 2].map(|k| x.com[k] - c[k]);
        let dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let mut out = x.inertia;
        for (i, row) in out.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                let delta = if i == j { dd } else { 0.0 };
                *v += x.mass * (delta - d[i] * d[j]);
            }
        }
        out
    };
    let (ia, ib) = (shift(&a), shift(&b));
    let mut inertia = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            inertia[i][j] = ia[i][j] + ib[i][j];
        }
    }
    Inertial {
        mass: m,
        com: c,
        inertia,
    }
}

/// Whether `n` is the URDF element `tag`: an element of that local name in no namespace or in
/// the `<robot>` element's own (`<robot xmlns="…">`, `<urdf:robot xmlns:urdf="…">`), so that
/// another tool's elements of the same name (`<gz:link>`) are ignored like any unknown element.
fn is_urdf(n: &roxmltree::Node<'_, '_>, tag: &str) -> bool {
    let ns = n.tag_name().namespace();
    n.is_element()
        && n.tag_name().name() == tag
        && (ns.is_none() || ns == n.document().root_element().tag_name().namespace())
}

/// Reads the chain `base` → `tip` of the URDF text `text` (`file` names it in errors). `base`
/// defaults to the root link, `tip` to the only leaf of a tree that does not branch.
///
/// Each model link's lumped inertia must be positive definite and satisfy the triangle
/// inequality of its principal moments, or the error names the URDF link. `nonphysical`,
/// the source of published values that break the triangle inequality (a scene's
/// `nonphysical_inertia` key), keeps such links as they are, marked with that source.
pub fn read_chain(
    text: &str,
    file: &str,
    base: Option<&str>,
    tip: Option<&str>,
    nonphysical: Option<&str>,
) -> Result<UrdfChain, SpecError> {
    // A document type declaration is well-formed XML that some exporters write; roxmltree
    // refuses one unless asked (it still guards against entity expansion attacks).
    let options = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..roxmltree::ParsingOptions::default()
    };
    let doc = roxmltree::Document::parse_with_options(text, options).map_err(|e| {
        let p = e.pos();
        SpecError::Urdf(Box::new(UrdfError {
            file: file.to_string(),
            line: p.row as usize,
            column: p.col as usize,
            element: "(document)".to_string(),
            attribute: String::new(),
            message: format!("not well-formed XML: {e}"),
        }))
    })?;
    let rd = Reader { file, doc: &doc };
    let root = doc.root_element();
    if root.tag_name().name() != "robot" {
        return Err(rd.err(
            root.range().start,
            root.tag_name().name(),
            "",
            "the root element must be <robot>".to_string(),
        ));
    }
    let robot = root.attribute("name").unwrap_or("robot").to_string();
    let elems = |tag: &'static str| root.children().filter(move |c| is_urdf(c, tag));
    // The chain's ends first: a name the caller gave wrongly is reported before anything in
    // the file, so that it is blamed on whoever gave it. An end found here is the index of its
    // `<link>` element, which is its index in `links` below (one link per element, in order).
    let names: Vec<Option<&str>> = elems("link").map(|n| n.attribute("name")).collect();
    let index_of = |name: &str| names.iter().position(|k| *k == Some(name));
    let (base_at, tip_at) = (
        base.map(|b| (b, index_of(b))),
        tip.map(|t| (t, index_of(t))),
    );
    let unknown: Vec<(ChainEnd, String)> = [(ChainEnd::Base, base_at), (ChainEnd::Tip, tip_at)]
        .into_iter()
        .filter_map(|(end, at)| match at {
            Some((name, None)) => Some((end, name.to_string())),
            _ => None,
        })
        .collect();
    if !unknown.is_empty() {
        let p = doc.text_pos_at(root.range().start);
        return Err(SpecError::UnknownLink(Box::new(UnknownLink {
            file: file.to_string(),
            line: p.row as usize,
            column: p.col as usize,
            unknown,
            links: names.iter().flatten().map(|n| n.to_string()).collect(),
        })));
    }
    let mut links: Vec<Link> = Vec::new();
    for n in elems("link") {
        let l = rd.link(n)?;
        if links.iter().any(|k| k.name == l.name) {
            return Err(rd.node_err(n, "name", format!("link {:?} is defined twice", l.name)));
        }
        links.push(l);
    }
    if links.is_empty() {
        return Err(rd.err(
            root.range().start,
            "robot",
            "",
            "no <link> elements".to_string(),
        ));
    }
    let mut joints: Vec<Joint> = Vec::new();
    let mut parent_joint: Vec<Option<usize>> = vec![None; links.len()];
    for n in elems("joint") {
        let j = rd.joint(n, &links)?;
        // Joint names key the scene's links and the kernels' variables, as link names do.
        if joints.iter().any(|k| k.name == j.name) {
            return Err(rd.node_err(n, "name", format!("joint {:?} is defined twice", j.name)));
        }
        if let Some(other) = parent_joint[j.child] {
            return Err(rd.node_err(
                n,
                "child",
                format!(
                    "link {:?} is the child of joints {:?} and {:?}: a closed loop (URDF \
                     describes trees only)",
                    links[j.child].name, joints[other].name, j.name
                ),
            ));
        }
        parent_joint[j.child] = Some(joints.len());
        joints.push(j);
    }
    // Loops: walking up from any link must reach a root.
    for start in 0..links.len() {
        let mut l = start;
        for _ in 0..=links.len() {
            match parent_joint[l] {
                None => break,
                Some(j) => l = joints[j].parent,
            }
            if l == start {
                let j = &joints[parent_joint[start].unwrap_or(0)];
                return Err(rd.err(
                    j.pos,
                    "joint",
                    "child",
                    format!(
                        "link {:?} is its own ancestor: the joints form a loop",
                        links[start].name
                    ),
                ));
            }
        }
    }
    let roots: Vec<usize> = (0..links.len())
        .filter(|&l| parent_joint[l].is_none())
        .collect();
    if roots.len() > 1 {
        let names: Vec<&str> = roots.iter().map(|&l| links[l].name.as_str()).collect();
        return Err(rd.err(
            links[roots[1]].pos,
            "link",
            "name",
            format!(
                "the links form {} trees (roots {names:?}); a robot has one root link",
                roots.len()
            ),
        ));
    }
    let children = |l: usize| -> Vec<usize> {
        (0..joints.len())
            .filter(|&j| joints[j].parent == l)
            .collect()
    };
    let base_ix = match base_at {
        Some((_, Some(ix))) => ix,
        _ => roots[0],
    };
    let tip_ix = match tip_at {
        Some((_, Some(ix))) => ix,
        _ => {
            let mut l = base_ix;
            loop {
                let c = children(l);
                match c.len() {
                    0 => break l,
                    1 => l = joints[c[0]].child,
                    _ => {
                        let names: Vec<&str> = c
                            .iter()
                            .map(|&j| links[joints[j].child].name.as_str())
                            .collect();
                        return Err(rd.err(
                            links[l].pos,
                            "link",
                            "name",
                            format!(
                                "the tree branches at link {:?} (children {names:?}): name the \
                                 tip link (--tip LINK, or tip_link in a scene)",
                                links[l].name
                            ),
                        ));
                    }
                }
            }
        }
    };
    // Where the base link sits: the joints from the root down to it, the moving ones locked at
    // q = 0 (their motion is then the identity, so only their origins count).
    let mut above: Vec<usize> = Vec::new();
    let mut l = base_ix;
    while let Some(j) = parent_joint[l] {
        above.push(j);
        l = joints[j].parent;
    }
    let root_ix = l;
    let base_pose = above
        .iter()
        .rev()
        .fold((I3, [0.0; 3]), |p, &j| compose(&p, &joints[j].origin));
    // The chain: joints from base to tip.
    let mut chain: Vec<usize> = Vec::new();
    let mut l = tip_ix;
    while l != base_ix {
        let Some(j) = parent_joint[l] else {
            return Err(rd.err(
                links[tip_ix].pos,
                "link",
                "name",
                format!(
                    "link {:?} is not on any chain from base link {:?}",
                    links[tip_ix].name, links[base_ix].name
                ),
            ));
        };
        chain.push(j);
        l = joints[j].parent;
    }
    chain.reverse();
    let moving: Vec<usize> = chain
        .iter()
        .copied()
        .filter(|&j| joints[j].kind != JointKind::Fixed)
        .collect();
    if moving.is_empty() {
        return Err(rd.err(
            links[tip_ix].pos,
            "link",
            "name",
            format!(
                "the chain from {:?} to {:?} has no revolute, continuous or prismatic joint",
                links[base_ix].name, links[tip_ix].name
            ),
        ));
    }
    // Owner (model link, or None for the base side) and pose in the owner's frame of every
    // link below the base, walking the tree from the base.
    let mut owner: Vec<Option<(Option<usize>, Pose)>> = vec![None; links.len()];
    owner[base_ix] = Some((None, (I3, [0.0; 3])));
    let mut stack = vec![base_ix];
    while let Some(p) = stack.pop() {
        let Some((own, pose)) = owner[p] else {
            continue;
        };
        for j in children(p) {
            let jt = &joints[j];
            let entry = match moving.iter().position(|&m| m == j) {
                Some(k) => (Some(k), (I3, [0.0; 3])),
                // Fixed, or off the chain and locked at q = 0: the origin only.
                None => (own, compose(&pose, &jt.origin)),
            };
            owner[jt.child] = Some(entry);
            stack.push(jt.child);
        }
    }
    let mut lumped: Vec<Option<Inertial>> = vec![None; moving.len()];
    for (l, o) in owner.iter().enumerate() {
        let (Some((Some(k), (r, t))), Some(b)) = (o, &links[l].inertial) else {
            continue;
        };
        let moved = Inertial {
            mass: b.mass,
            com: {
                let rc = mat_vec(r, b.com);
                [0, 1, 2].map(|i| rc[i] + t[i])
            },
            inertia: rotate_tensor(r, &b.inertia),
        };
        lumped[*k] = Some(lump(lumped[*k].take(), moved));
    }
    let mut out = Vec::with_capacity(moving.len());
    let mut link_positions = Vec::with_capacity(moving.len());
    // Placement of joint k: the chain's origins from the previous moving joint's child.
    let mut pose = (I3, [0.0; 3]);
    let mut k = 0;
    for &j in &chain {
        let jt = &joints[j];
        pose = compose(&pose, &jt.origin);
        if jt.kind == JointKind::Fixed {
            continue;
        }
        let c = &links[jt.child];
        let Some(body) = lumped[k].clone() else {
            let what = if c.massless_inertial {
                "has mass 0 (a massless <inertial>, as none)"
            } else {
                "has no <inertial>"
            };
            return Err(rd.err(
                c.pos,
                "link",
                "inertial",
                format!(
                    "link {:?} (moved by joint {:?}) {what}, nor has any link fixed to it: a \
                     moving link needs a mass",
                    c.name, jt.name
                ),
            ));
        };
        let bodies: Vec<&Link> = owner
            .iter()
            .zip(&links)
            .filter(|(o, l)| l.inertial.is_some() && matches!(o, Some((Some(i), _)) if *i == k))
            .map(|(_, l)| l)
            .collect();
        let lumped_note = if bodies.len() > 1 {
            " (with the links fixed to it)"
        } else {
            ""
        };
        if body.inertia.iter().flatten().all(|&x| x == 0.0) {
            // Point the user at the <inertia> they wrote: the link's own, or, when it has none,
            // that of the body fixed to it.
            let at = bodies
                .iter()
                .find(|l| l.name == c.name)
                .or(bodies.first())
                .copied()
                .unwrap_or(c);
            let whose = if at.name == c.name {
                String::new()
            } else {
                format!(" (the <inertia> of link {:?}, fixed to it)", at.name)
            };
            return Err(rd.err(
                at.inertia_pos,
                "inertia",
                "",
                format!(
                    "link {:?}{lumped_note}, moved by joint {:?}: the inertia is zero while the \
                     mass is {} kg > 0{whose}; a moving link's inertia must be positive definite \
                     (a point mass has no rotational inertia)",
                    c.name, jt.name, body.mass
                ),
            ));
        }
        if let Some(msg) = crate::validate::definiteness_violation(&body.inertia) {
            return Err(rd.err(
                c.pos,
                "link",
                "inertial",
                format!(
                    "link {:?}{lumped_note}, moved by joint {:?}: {msg}",
                    c.name, jt.name
                ),
            ));
        }
        let triangle = crate::validate::triangle_violation(&body.inertia);
        if let (Some(msg), None) = (&triangle, nonphysical) {
            return Err(rd.err(
                c.pos,
                "link",
                "inertial",
                format!(
                    "link {:?}{lumped_note}, moved by joint {:?}: {msg}; correct its \
                     <inertia>, or keep the URDF's values by naming their source with \
                     `nonphysical_inertia = \"...\"` beside `urdf` in a scene file \
                     (docs/scene-format.md)",
                    c.name, jt.name
                ),
            ));
        }
        let (q_min, q_max, tau_max) = match jt.limit {
            Some((lo, hi, effort)) if lo < hi => {
                (Some(lo), Some(hi), (effort > 0.0).then_some(effort))
            }
            Some((_, _, effort)) => (None, None, (effort > 0.0).then_some(effort)),
            None => (None, None, None),
        };
        out.push(LinkSpec {
            name: Some(jt.name.clone()),
            joint: if jt.kind == JointKind::Prismatic {
                JointType::Prismatic
            } else {
                JointType::Revolute
            },
            a: 0.0,
            alpha: crate::Angle::Radians(0.0),
            d: 0.0,
            offset: None,
            origin: Some(TransformSpec {
                translation: Some(pose.1),
                rotation: Some(RotationSpec::Matrix(pose.0)),
            }),
            axis: Some(jt.axis),
            mass: body.mass,
            com: body.com,
            inertia: InertiaSpec::Full(body.inertia),
            nonphysical_inertia: triangle.and(nonphysical.map(str::to_string)),
            q_min,
            q_max,
            tau_max,
        });
        let p = doc.text_pos_at(c.pos);
        link_positions.push((p.row as usize, p.col as usize));
        pose = (I3, [0.0; 3]);
        k += 1;
    }
    let tool = (pose != (I3, [0.0; 3])).then_some(TransformSpec {
        translation: Some(pose.1),
        rotation: Some(RotationSpec::Matrix(pose.0)),
    });
    Ok(UrdfChain {
        robot,
        root_link: links[root_ix].name.clone(),
        base_link: links[base_ix].name.clone(),
        tip_link: links[tip_ix].name.clone(),
        base: (base_pose != (I3, [0.0; 3])).then_some(TransformSpec {
            translation: Some(base_pose.1),
            rotation: Some(RotationSpec::Matrix(base_pose.0)),
        }),
        links: out,
        tool,
        joint_names: moving.iter().map(|&j| joints[j].name.clone()).collect(),
        link_positions,
    })
}
