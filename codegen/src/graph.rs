//! Expression graph: a hash-consed arena of scalar expressions (`docs/architecture.md`, "Graph").
//!
//! Every symbol of the paper (p_e and ê_x3 of eq. 67–68, the Jacobians of eq. 69–71, M of
//! eq. 22a/74, C of eq. 76–79, g of eq. 72–73, the contact quantities of eq. 2–13 and 58–59)
//! is built as nodes of one [`Graph`]. Nodes are stored children-before-parents, so the
//! arena index order is a topological order. Construction goes through the `Graph` methods,
//! which fold constants and apply algebraic identities (x·0, x·1, x+0, x−x, −(−x), …) and then
//! look the node up in a memo table, so equal subexpressions are one node (CSE for free).
//!
//! Size: a graph holds at most [`Graph::limit`] nodes ([`DEFAULT_NODE_LIMIT`],
//! [`set_node_limit`]); past it, construction yields one NaN constant (the poison) and
//! [`Graph::exceeded`] is true, which the builders of kernels and node functions report.
//!
//! Exact constants: DH angles that are rational multiples of π are folded through
//! [`Graph::cos_pi`] / [`Graph::sin_pi`], which return exactly 0, ±1, ±½ where those are the
//! true values, so cos(π/2) is exactly 0 and whole subtrees vanish.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hash, Hasher};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Nodes a [`Graph`] holds at most unless [`set_node_limit`] says otherwise: 2²⁴ ≈ 16.8 million,
/// some 500 times the largest built-in scene's graph (the 7-joint arm's 34 thousand nodes).
/// Generating or evaluating a robot's kernels takes about 250–370 bytes per node at its peak
/// (the graph, its memo table, the interpreter's tape or the emitted text; BENCHMARKS.md,
/// "Expression graphs of long chains"), so a request that would grow past about 6 GiB ends
/// with an error that names it instead of exhausting the machine: with every kernel, a chain
/// of some 48 joints.
pub const DEFAULT_NODE_LIMIT: usize = 1 << 24;

/// The node limit of graphs created from now on in this process ([`set_node_limit`]).
static NODE_LIMIT: AtomicUsize = AtomicUsize::new(DEFAULT_NODE_LIMIT);

/// Sets the node limit of the graphs this process creates from now on (at least 1, below
/// `u32::MAX`; [`DEFAULT_NODE_LIMIT`] until set): the CLI's `--max-graph-nodes`.
pub fn set_node_limit(limit: usize) {
    NODE_LIMIT.store(clamp_limit(limit), Ordering::Relaxed);
}

/// A node limit that leaves the poison an id: 1 ..= u32::MAX − 1.
fn clamp_limit(limit: usize) -> usize {
    limit.clamp(1, u32::MAX as usize - 1)
}

/// The node limit that a graph created now gets ([`set_node_limit`]).
pub fn node_limit() -> usize {
    NODE_LIMIT.load(Ordering::Relaxed)
}

/// A multiply–rotate hasher for the memo table (the scheme of rustc's `FxHasher`): the keys are
/// small fixed-size nodes made by this program, so SipHash's defence against chosen keys buys
/// nothing, and interning is a hot loop of the symbolic differentiation. Deterministic (no
/// random seed); the table is only looked up, never iterated, so nothing depends on its order.
#[derive(Default, Clone, Copy)]
struct NodeHasher(u64);

const NODE_HASH_K: u64 = 0x51_7c_c1_b7_27_22_0a_95;

impl NodeHasher {
    fn add(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(NODE_HASH_K);
    }
}

impl Hasher for NodeHasher {
    fn write(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for c in &mut chunks {
            let mut w = [0u8; 8];
            w.copy_from_slice(c);
            self.add(u64::from_le_bytes(w));
        }
        for &b in chunks.remainder() {
            self.add(b as u64);
        }
    }
    fn write_u8(&mut self, x: u8) {
        self.add(x as u64);
    }
    fn write_u32(&mut self, x: u32) {
        self.add(x as u64);
    }
    fn write_u64(&mut self, x: u64) {
        self.add(x);
    }
    fn write_usize(&mut self, x: usize) {
        self.add(x as u64);
    }
    fn write_isize(&mut self, x: isize) {
        self.add(x as u64);
    }
    fn finish(&self) -> u64 {
        self.0
    }
}

/// The node list so far, as its length and a 128-bit hash of every node in order
/// ([`Graph::history`]): two graphs with the same history hold the same nodes with the same
/// ids (up to a hash collision), so any deterministic construction on them adds the same
/// nodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct History {
    /// Number of nodes.
    pub len: usize,
    /// Hash of the nodes in id order.
    pub hash: u128,
}

/// Index of a node in a [`Graph`] arena.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Id(pub u32);

impl Id {
    /// The arena index as `usize`.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// One scalar operation. Children always have smaller ids than the node itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Node {
    /// A constant, stored as the bits of an `f64` (never `-0.0`).
    Const(u64),
    /// An input variable (see the front-end for the layout: q, q̇, ω, ε, parameters).
    Var(u32),
    /// a + b
    Add(Id, Id),
    /// a − b
    Sub(Id, Id),
    /// a · b
    Mul(Id, Id),
    /// a / b
    Div(Id, Id),
    /// −a
    Neg(Id),
    /// sin a
    Sin(Id),
    /// cos a
    Cos(Id),
    /// √a
    Sqrt(Id),
    /// |a|
    Abs(Id),
    /// min(a, b) (`f64::min`)
    Min(Id, Id),
    /// max(a, b) (`f64::max`)
    Max(Id, Id),
    /// `if a < b { t } else { f }` (used by derivatives of abs/min/max).
    IfLt(Id, Id, Id, Id),
}

impl Node {
    /// The children of the node, in operand order.
    pub fn children(&self) -> impl Iterator<Item = Id> {
        let (arr, n): ([Id; 4], usize) = match *self {
            Node::Const(_) | Node::Var(_) => ([Id(0); 4], 0),
            Node::Neg(a) | Node::Sin(a) | Node::Cos(a) | Node::Sqrt(a) | Node::Abs(a) => {
                ([a, Id(0), Id(0), Id(0)], 1)
            }
            Node::Add(a, b)
            | Node::Sub(a, b)
            | Node::Mul(a, b)
            | Node::Div(a, b)
            | Node::Min(a, b)
            | Node::Max(a, b) => ([a, b, Id(0), Id(0)], 2),
            Node::IfLt(a, b, t, f) => ([a, b, t, f], 4),
        };
        arr.into_iter().take(n)
    }
}

/// A hash-consed expression arena.
///
/// It holds at most [`Graph::limit`] nodes. A construction that would add more gets, for every
/// node it would add, one constant NaN (the *poison*, the one node beyond the limit), and the graph says so
/// ([`Graph::exceeded`]): its memory stays bounded, whatever still uses it evaluates to NaN
/// ([`crate::interp::Tape::new`] of an exceeded graph computes NaN for every output), and the
/// builders that finish a kernel turn it into an error that names what grew too large.
#[derive(Debug, Clone)]
pub struct Graph {
    nodes: Vec<Node>,
    memo: HashMap<Node, Id, BuildHasherDefault<NodeHasher>>,
    /// Running hash of `nodes` ([`History`]), two lanes.
    history: [u64; 2],
    /// Nodes at most ([`node_limit`] when the graph was created).
    limit: usize,
    /// The NaN constant that stands for every node beyond the limit, once one was asked for.
    poison: Option<Id>,
}

impl Default for Graph {
    fn default() -> Self {
        Graph {
            nodes: Vec::new(),
            memo: HashMap::default(),
            history: [0; 2],
            limit: node_limit(),
            poison: None,
        }
    }
}

fn norm_bits(v: f64) -> u64 {
    if v == 0.0 {
        0.0f64.to_bits()
    } else {
        v.to_bits()
    }
}

/// Exact cos(num/den · π) where it is 0, ±1 or ±½; otherwise the `f64` value
/// (√2/2 and √3/2 as correctly rounded square roots).
pub fn cos_pi_value(num: i64, den: i64) -> f64 {
    debug_assert!(den > 0);
    // Reduce num/den mod 2 exactly: angle = (num mod 2den)/den · π.
    let two_den = 2 * den as i128;
    let r = (num as i128).rem_euclid(two_den);
    // cos is determined by r/den in [0, 2).
    let g = gcd(r, den as i128).max(1);
    let (rn, rd) = (r / g, den as i128 / g);
    match (rn, rd) {
        (0, _) => 1.0,
        (1, 1) => -1.0,
        (1, 2) | (3, 2) => 0.0,
        (1, 3) | (5, 3) => 0.5,
        (2, 3) | (4, 3) => -0.5,
        (1, 4) | (7, 4) => 0.5f64.sqrt(),
        (3, 4) | (5, 4) => -(0.5f64.sqrt()),
        (1, 6) | (11, 6) => 3.0f64.sqrt() * 0.5,
        (5, 6) | (7, 6) => -(3.0f64.sqrt() * 0.5),
        _ => libm::cos(rn as f64 / rd as f64 * std::f64::consts::PI),
    }
}

/// Exact sin(num/den · π), via sin x = cos(x − π/2).
pub fn sin_pi_value(num: i64, den: i64) -> f64 {
    // num/den − 1/2 = (2num − den)/(2den)
    cos_pi_value(2 * num - den, 2 * den)
}

fn gcd(a: i128, b: i128) -> i128 {
    let (mut a, mut b) = (a.abs(), b.abs());
    while b != 0 {
        let t = a % b;
        a = b;
        b = t;
    }
    a
}

impl Graph {
    /// An empty graph with the process's node limit ([`node_limit`]).
    pub fn new() -> Self {
        Self::default()
    }

    /// An empty graph that holds at most `limit` nodes (at least 1, below `u32::MAX`).
    pub fn with_limit(limit: usize) -> Self {
        Graph {
            limit: clamp_limit(limit),
            ..Self::default()
        }
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True if there are no nodes.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Nodes this graph holds at most.
    pub fn limit(&self) -> usize {
        self.limit
    }

    /// True once a construction asked for more than [`Graph::limit`] nodes: the expressions
    /// built since then contain the NaN poison in place of the nodes that did not fit, so
    /// nothing built on this graph may be used.
    pub fn exceeded(&self) -> bool {
        self.poison.is_some()
    }

    /// The poison if the graph was exceeded, so that evaluations of an exceeded graph give NaN.
    pub fn poison(&self) -> Option<Id> {
        self.poison
    }

    /// The node with id `id`.
    pub fn node(&self, id: Id) -> Node {
        self.nodes[id.index()]
    }

    /// All nodes in topological order.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    fn intern(&mut self, n: Node) -> Id {
        if let Some(&id) = self.memo.get(&n) {
            return id;
        }
        self.push_new(n)
    }

    /// Appends `n`, which the graph does not hold yet; past the limit, returns the poison
    /// instead (pushed once, the one node beyond the limit).
    fn push_new(&mut self, n: Node) -> Id {
        if let Some(p) = self.poison {
            return p;
        }
        if self.nodes.len() >= self.limit {
            let nan = Node::Const(f64::NAN.to_bits());
            let p = match self.memo.get(&nan) {
                Some(&p) => p,
                None => self.push_unchecked(nan),
            };
            self.poison = Some(p);
            return p;
        }
        self.push_unchecked(n)
    }

    fn push_unchecked(&mut self, n: Node) -> Id {
        // The limit is below u32::MAX, so the index (of the poison too) fits.
        let id = Id(self.nodes.len() as u32);
        self.nodes.push(n);
        self.memo.insert(n, id);
        let mut h = NodeHasher::default();
        n.hash(&mut h);
        let x = h.finish();
        self.history[0] = (self.history[0] ^ x).wrapping_mul(0x0000_0100_0000_01b3);
        self.history[1] = (self.history[1].rotate_left(17) ^ x).wrapping_mul(NODE_HASH_K);
        id
    }

    /// The nodes so far as a [`History`]: what a deterministic construction on this graph
    /// depends on.
    pub fn history(&self) -> History {
        History {
            len: self.nodes.len(),
            hash: ((self.history[0] as u128) << 64) | self.history[1] as u128,
        }
    }

    /// Appends `nodes` in order, as a construction that added them to a graph of this
    /// graph's history did (each interned: a node already present keeps its id, which such
    /// a construction never produced).
    pub fn extend_with(&mut self, nodes: &[Node]) {
        self.nodes.reserve(nodes.len());
        self.memo.reserve(nodes.len());
        for &n in nodes {
            if !self.memo.contains_key(&n) {
                self.push_new(n);
            }
        }
    }

    /// The constant `v` (−0.0 is stored as 0.0).
    pub fn constant(&mut self, v: f64) -> Id {
        self.intern(Node::Const(norm_bits(v)))
    }

    /// The constant 0.
    pub fn zero(&mut self) -> Id {
        self.constant(0.0)
    }

    /// The constant 1.
    pub fn one(&mut self) -> Id {
        self.constant(1.0)
    }

    /// Input variable number `i`.
    pub fn var(&mut self, i: u32) -> Id {
        self.intern(Node::Var(i))
    }

    /// The value of `id` if it is a constant.
    pub fn as_const(&self, id: Id) -> Option<f64> {
        match self.nodes[id.index()] {
            Node::Const(b) => Some(f64::from_bits(b)),
            _ => None,
        }
    }

    /// True if `id` is the constant `v`.
    pub fn is_const(&self, id: Id, v: f64) -> bool {
        self.as_const(id) == Some(v)
    }

    /// True if `id` is the constant 0 (a structural zero).
    pub fn is_zero(&self, id: Id) -> bool {
        self.is_const(id, 0.0)
    }

    fn neg_inner(&self, id: Id) -> Option<Id> {
        match self.nodes[id.index()] {
            Node::Neg(x) => Some(x),
            _ => None,
        }
    }

    /// `id` as `c ± x` with a nonzero constant c and a non-constant x, if it has that form.
    fn split(&self, id: Id) -> Option<(f64, bool, Id)> {
        match self.nodes[id.index()] {
            Node::Add(a, b) => match (self.as_const(a), self.as_const(b)) {
                (Some(c), None) => Some((c, false, b)),
                (None, Some(c)) => Some((c, false, a)),
                _ => None,
            },
            Node::Sub(a, b) => match (self.as_const(a), self.as_const(b)) {
                (Some(c), None) => Some((c, true, b)),
                (None, Some(c)) => Some((-c, false, a)),
                _ => None,
            },
            _ => None,
        }
    }

    /// (constant part, optional signed term) of `id`.
    fn lin(&self, id: Id) -> (f64, Option<(bool, Id)>) {
        if let Some(c) = self.as_const(id) {
            return (c, None);
        }
        match self.split(id) {
            Some((c, neg, x)) => (c, Some((neg, x))),
            None => (0.0, Some((false, id))),
        }
    }

    /// a + s·b (s = ±1) with constants pulled outward: (c1 ± x1) + s(c2 ± x2) =
    /// (c1 + s c2) + (±x1 ± x2), so chains like −0.5 − (−1 − x) fold to 0.5 + x.
    fn add_reassoc(&mut self, a: Id, b: Id, negate_b: bool) -> Option<Id> {
        if self.split(a).is_none() && self.split(b).is_none() {
            return None;
        }
        let (ca, ta) = self.lin(a);
        let (cb, tb) = self.lin(b);
        let c = if negate_b { ca - cb } else { ca + cb };
        let tb = tb.map(|(n, x)| (n != negate_b, x));
        // Combine the signed terms (no constant parts, so no further reassociation).
        let term: Option<(bool, Id)> = match (ta, tb) {
            (None, None) => None,
            (Some(t), None) | (None, Some(t)) => Some(t),
            (Some((na, xa)), Some((nb, xb))) => Some(match (na, nb) {
                (false, false) => (false, self.add(xa, xb)),
                (false, true) => (false, self.sub(xa, xb)),
                (true, false) => (false, self.sub(xb, xa)),
                (true, true) => (true, self.add(xa, xb)),
            }),
        };
        let Some((neg, x)) = term else {
            return Some(self.constant(c));
        };
        let cst = self.constant(c);
        Some(if neg {
            self.sub(cst, x)
        } else {
            self.add(x, cst)
        })
    }

    /// Expand `id` (times `coef`) into linear terms (node, coefficient) and a constant:
    /// through sums, differences, negations and constant multiples, at most `depth` levels.
    fn expand(&self, id: Id, coef: f64, depth: u32, terms: &mut Vec<(Id, f64)>, cst: &mut f64) {
        match self.nodes[id.index()] {
            Node::Const(b) => *cst += coef * f64::from_bits(b),
            Node::Add(a, b) if depth > 0 => {
                self.expand(a, coef, depth - 1, terms, cst);
                self.expand(b, coef, depth - 1, terms, cst);
            }
            Node::Sub(a, b) if depth > 0 => {
                self.expand(a, coef, depth - 1, terms, cst);
                self.expand(b, -coef, depth - 1, terms, cst);
            }
            Node::Neg(a) if depth > 0 => self.expand(a, -coef, depth - 1, terms, cst),
            Node::Mul(c, x) if self.as_const(c).is_some() => {
                let k = self.as_const(c).unwrap_or(1.0);
                terms.push((x, coef * k));
            }
            _ => terms.push((id, coef)),
        }
    }

    /// a ± b as a collected linear combination, if collecting merges or cancels terms
    /// (e.g. 2x − (x + y) → x − y); `None` leaves the sum to the plain rules.
    fn collect_sum(&mut self, a: Id, b: Id, negate_b: bool) -> Option<Id> {
        const DEPTH: u32 = 3;
        const MAX_TERMS: usize = 8;
        let mut terms = Vec::new();
        let mut cst = 0.0;
        self.expand(a, 1.0, DEPTH, &mut terms, &mut cst);
        self.expand(
            b,
            if negate_b { -1.0 } else { 1.0 },
            DEPTH,
            &mut terms,
            &mut cst,
        );
        if terms.len() > MAX_TERMS || terms.len() < 2 {
            return None;
        }
        terms.sort_by_key(|t| t.0);
        let before = terms.len();
        let mut merged: Vec<(Id, f64)> = Vec::with_capacity(before);
        for (id, c) in terms {
            match merged.last_mut() {
                Some(last) if last.0 == id => last.1 += c,
                _ => merged.push((id, c)),
            }
        }
        if merged.len() == before {
            return None;
        }
        merged.retain(|t| t.1 != 0.0);
        // Rebuild: positive terms first (in id order), then subtract the negative ones.
        let mut acc: Option<Id> = None;
        for &(id, c) in merged.iter().filter(|t| t.1 > 0.0) {
            let k = self.constant(c);
            let t = self.mul(k, id);
            acc = Some(match acc {
                None => t,
                Some(x) => self.add(x, t),
            });
        }
        for &(id, c) in merged.iter().filter(|t| t.1 < 0.0) {
            let k = self.constant(-c);
            let t = self.mul(k, id);
            acc = Some(match acc {
                None => self.neg(t),
                Some(x) => self.sub(x, t),
            });
        }
        let k = self.constant(cst);
        Some(match acc {
            None => k,
            Some(x) => self.add(x, k),
        })
    }

    /// a + b
    pub fn add(&mut self, a: Id, b: Id) -> Id {
        match (self.as_const(a), self.as_const(b)) {
            (Some(x), Some(y)) => return self.constant(x + y),
            (Some(0.0), _) => return b,
            (_, Some(0.0)) => return a,
            _ => {}
        }
        if a == b {
            let two = self.constant(2.0);
            return self.mul(two, a);
        }
        if let Some(r) = self.collect_sum(a, b, false) {
            return r;
        }
        if let Some(r) = self.add_reassoc(a, b, false) {
            return r;
        }
        match (self.neg_inner(a), self.neg_inner(b)) {
            (Some(x), Some(y)) => {
                let s = self.add(x, y);
                return self.neg(s);
            }
            (Some(x), None) => return self.sub(b, x),
            (None, Some(y)) => return self.sub(a, y),
            _ => {}
        }
        // Negative constants are pulled out as subtraction so `x + (-c)` and `x - c` share.
        if let Some(y) = self.as_const(b)
            && y < 0.0
        {
            let c = self.constant(-y);
            return self.sub(a, c);
        }
        if let Some(x) = self.as_const(a)
            && x < 0.0
        {
            let c = self.constant(-x);
            return self.sub(b, c);
        }
        let (a, b) = if a <= b { (a, b) } else { (b, a) };
        self.intern(Node::Add(a, b))
    }

    /// a − b
    pub fn sub(&mut self, a: Id, b: Id) -> Id {
        if a == b {
            return self.zero();
        }
        match (self.as_const(a), self.as_const(b)) {
            (Some(x), Some(y)) => return self.constant(x - y),
            (Some(0.0), _) => return self.neg(b),
            (_, Some(0.0)) => return a,
            _ => {}
        }
        if let Some(r) = self.collect_sum(a, b, true) {
            return r;
        }
        if let Some(r) = self.add_reassoc(a, b, true) {
            return r;
        }
        if let Some(y) = self.neg_inner(b) {
            return self.add(a, y);
        }
        if let Some(x) = self.neg_inner(a) {
            let s = self.add(x, b);
            return self.neg(s);
        }
        if let Some(y) = self.as_const(b)
            && y < 0.0
        {
            let c = self.constant(-y);
            return self.add(a, c);
        }
        self.intern(Node::Sub(a, b))
    }

    /// a · b
    pub fn mul(&mut self, a: Id, b: Id) -> Id {
        let (a, b) = if self.as_const(b).is_some() && self.as_const(a).is_none() {
            (b, a)
        } else {
            (a, b)
        };
        match (self.as_const(a), self.as_const(b)) {
            (Some(x), Some(y)) => return self.constant(x * y),
            (Some(0.0), _) => return self.zero(),
            (Some(1.0), _) => return b,
            (Some(-1.0), _) => return self.neg(b),
            (Some(x), _) if x < 0.0 => {
                let c = self.constant(-x);
                let m = self.mul(c, b);
                return self.neg(m);
            }
            _ => {}
        }
        if let Some(x) = self.neg_inner(a) {
            let m = self.mul(x, b);
            return self.neg(m);
        }
        if let Some(y) = self.neg_inner(b) {
            let m = self.mul(a, y);
            return self.neg(m);
        }
        // c1 · (c2 · x) → (c1 c2) · x, so scaled copies of one term share a node.
        if let Some(x) = self.as_const(a)
            && let Node::Mul(c2, y) = self.nodes[b.index()]
            && let Some(x2) = self.as_const(c2)
        {
            let c = self.constant(x * x2);
            return self.mul(c, y);
        }
        // Constant factors float to the top of products: x·(c·y) → c·(x·y), so products
        // differing only in where a constant sits (product rule) share one node.
        if self.as_const(a).is_none() {
            if let Node::Mul(c, y) = self.nodes[b.index()]
                && self.as_const(c).is_some()
            {
                let xy = self.mul(a, y);
                return self.mul(c, xy);
            }
            if let Node::Mul(c, x) = self.nodes[a.index()]
                && self.as_const(c).is_some()
            {
                let xy = self.mul(x, b);
                return self.mul(c, xy);
            }
        }
        let (a, b) = if self.as_const(a).is_some() || a <= b {
            (a, b)
        } else {
            (b, a)
        };
        self.intern(Node::Mul(a, b))
    }

    /// a / b
    pub fn div(&mut self, a: Id, b: Id) -> Id {
        match (self.as_const(a), self.as_const(b)) {
            (Some(x), Some(y)) => return self.constant(x / y),
            (Some(0.0), _) => return self.zero(),
            (_, Some(1.0)) => return a,
            (_, Some(-1.0)) => return self.neg(a),
            (_, Some(y)) if y != 0.0 && y.is_finite() => {
                // Division by a power of two is an exact multiplication.
                let inv = 1.0 / y;
                let mantissa = y.to_bits() & ((1u64 << 52) - 1);
                if y.is_normal() && inv.is_normal() && mantissa == 0 {
                    let c = self.constant(inv);
                    return self.mul(c, a);
                }
            }
            _ => {}
        }
        if a == b {
            return self.one();
        }
        if let Some(x) = self.neg_inner(a) {
            let d = self.div(x, b);
            return self.neg(d);
        }
        if let Some(y) = self.neg_inner(b) {
            let d = self.div(a, y);
            return self.neg(d);
        }
        self.intern(Node::Div(a, b))
    }

    /// −a
    pub fn neg(&mut self, a: Id) -> Id {
        if let Some(x) = self.as_const(a) {
            return self.constant(-x);
        }
        match self.nodes[a.index()] {
            Node::Neg(x) => x,
            Node::Sub(x, y) => self.sub(y, x),
            _ => self.intern(Node::Neg(a)),
        }
    }

    /// sin a
    pub fn sin(&mut self, a: Id) -> Id {
        if let Some(x) = self.as_const(a) {
            return self.constant(libm::sin(x));
        }
        if let Some(x) = self.neg_inner(a) {
            let s = self.sin(x);
            return self.neg(s);
        }
        self.intern(Node::Sin(a))
    }

    /// cos a
    pub fn cos(&mut self, a: Id) -> Id {
        if let Some(x) = self.as_const(a) {
            return self.constant(libm::cos(x));
        }
        if let Some(x) = self.neg_inner(a) {
            return self.cos(x);
        }
        self.intern(Node::Cos(a))
    }

    /// The exact constant cos(num/den · π).
    pub fn cos_pi(&mut self, num: i64, den: i64) -> Id {
        self.constant(cos_pi_value(num, den))
    }

    /// The exact constant sin(num/den · π).
    pub fn sin_pi(&mut self, num: i64, den: i64) -> Id {
        self.constant(sin_pi_value(num, den))
    }

    /// √a
    pub fn sqrt(&mut self, a: Id) -> Id {
        if let Some(x) = self.as_const(a) {
            return self.constant(x.sqrt());
        }
        self.intern(Node::Sqrt(a))
    }

    /// |a|
    pub fn abs(&mut self, a: Id) -> Id {
        if let Some(x) = self.as_const(a) {
            return self.constant(x.abs());
        }
        match self.nodes[a.index()] {
            Node::Neg(x) => self.abs(x),
            Node::Abs(_) | Node::Sqrt(_) => a,
            _ => self.intern(Node::Abs(a)),
        }
    }

    /// min(a, b)
    pub fn min(&mut self, a: Id, b: Id) -> Id {
        if a == b {
            return a;
        }
        if let (Some(x), Some(y)) = (self.as_const(a), self.as_const(b)) {
            return self.constant(x.min(y));
        }
        self.intern(Node::Min(a, b))
    }

    /// max(a, b)
    pub fn max(&mut self, a: Id, b: Id) -> Id {
        if a == b {
            return a;
        }
        if let (Some(x), Some(y)) = (self.as_const(a), self.as_const(b)) {
            return self.constant(x.max(y));
        }
        self.intern(Node::Max(a, b))
    }

    /// `if a < b { t } else { f }`
    pub fn if_lt(&mut self, a: Id, b: Id, t: Id, f: Id) -> Id {
        if t == f {
            return t;
        }
        if let (Some(x), Some(y)) = (self.as_const(a), self.as_const(b)) {
            return if x < y { t } else { f };
        }
        self.intern(Node::IfLt(a, b, t, f))
    }

    /// sat_lo^hi(x) = min(max(x, lo), hi) (paper eq. 3).
    pub fn sat(&mut self, x: Id, lo: Id, hi: Id) -> Id {
        let m = self.max(x, lo);
        self.min(m, hi)
    }

    /// a².
    pub fn square(&mut self, a: Id) -> Id {
        self.mul(a, a)
    }

    /// Σ terms (left to right; empty sum is 0).
    pub fn sum(&mut self, terms: &[Id]) -> Id {
        let mut acc = self.zero();
        for &t in terms {
            acc = self.add(acc, t);
        }
        acc
    }

    /// Σ a_i b_i.
    pub fn dot(&mut self, a: &[Id], b: &[Id]) -> Id {
        debug_assert_eq!(a.len(), b.len());
        let mut acc = self.zero();
        for (&x, &y) in a.iter().zip(b) {
            let p = self.mul(x, y);
            acc = self.add(acc, p);
        }
        acc
    }

    /// Number of operations (non-constant, non-variable nodes) needed to evaluate `roots`.
    pub fn cost(&self, roots: &[Id]) -> usize {
        let mark = self.cone(roots);
        mark.iter()
            .zip(&self.nodes)
            .filter(|(m, n)| **m && !matches!(n, Node::Const(_) | Node::Var(_)))
            .count()
    }

    /// Mark every node in the cone (transitive children) of `roots`.
    pub fn cone(&self, roots: &[Id]) -> Vec<bool> {
        let Some(max) = roots.iter().map(|r| r.index()).max() else {
            return vec![false; self.nodes.len()];
        };
        let mut mark = vec![false; self.nodes.len()];
        for r in roots {
            mark[r.index()] = true;
        }
        for i in (0..=max).rev() {
            if mark[i] {
                for c in self.nodes[i].children() {
                    mark[c.index()] = true;
                }
            }
        }
        mark
    }
}

/// 3-vectors and 3×3 matrices of graph nodes (rigid-body algebra of Sect. 2 / App. A).
pub type V3 = [Id; 3];
/// A 3×3 matrix of nodes, row-major.
pub type M3 = [[Id; 3]; 3];

impl Graph {
    /// Constant vector.
    pub fn v3_const(&mut self, v: [f64; 3]) -> V3 {
        [
            self.constant(v[0]),
            self.constant(v[1]),
            self.constant(v[2]),
        ]
    }

    /// The zero vector.
    pub fn v3_zero(&mut self) -> V3 {
        let z = self.zero();
        [z, z, z]
    }

    /// a + b
    pub fn v3_add(&mut self, a: V3, b: V3) -> V3 {
        [
            self.add(a[0], b[0]),
            self.add(a[1], b[1]),
            self.add(a[2], b[2]),
        ]
    }

    /// a − b
    pub fn v3_sub(&mut self, a: V3, b: V3) -> V3 {
        [
            self.sub(a[0], b[0]),
            self.sub(a[1], b[1]),
            self.sub(a[2], b[2]),
        ]
    }

    /// s · a
    pub fn v3_scale(&mut self, s: Id, a: V3) -> V3 {
        [self.mul(s, a[0]), self.mul(s, a[1]), self.mul(s, a[2])]
    }

    /// a · b
    pub fn v3_dot(&mut self, a: V3, b: V3) -> Id {
        self.dot(&a, &b)
    }

    /// a × b
    pub fn v3_cross(&mut self, a: V3, b: V3) -> V3 {
        let mut c = [a[0]; 3];
        for (i, ci) in c.iter_mut().enumerate() {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let p = self.mul(a[j], b[k]);
            let q = self.mul(a[k], b[j]);
            *ci = self.sub(p, q);
        }
        c
    }

    /// Identity matrix.
    pub fn m3_identity(&mut self) -> M3 {
        let (z, o) = (self.zero(), self.one());
        [[o, z, z], [z, o, z], [z, z, o]]
    }

    /// A · v
    pub fn m3_mul_v(&mut self, a: &M3, v: V3) -> V3 {
        [
            self.dot(&a[0], &v),
            self.dot(&a[1], &v),
            self.dot(&a[2], &v),
        ]
    }

    /// Aᵀ · v
    pub fn m3_tmul_v(&mut self, a: &M3, v: V3) -> V3 {
        let t = m3_transpose(a);
        self.m3_mul_v(&t, v)
    }

    /// A · B
    pub fn m3_mul(&mut self, a: &M3, b: &M3) -> M3 {
        let bt = m3_transpose(b);
        let mut c = *a;
        for i in 0..3 {
            for j in 0..3 {
                c[i][j] = self.dot(&a[i], &bt[j]);
            }
        }
        c
    }
}

/// Aᵀ
pub fn m3_transpose(a: &M3) -> M3 {
    let mut t = *a;
    for i in 0..3 {
        for j in 0..3 {
            t[i][j] = a[j][i];
        }
    }
    t
}
