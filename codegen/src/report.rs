//! Generation report: per-kernel operation counts, the graph and code sizes and the total
//! generation time (`docs/architecture.md`, "Report").

use std::fmt;

/// Operation counts of one emitted kernel.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct OpCounts {
    /// Additions and subtractions.
    pub add: usize,
    /// Multiplications.
    pub mul: usize,
    /// Divisions.
    pub div: usize,
    /// Square roots.
    pub sqrt: usize,
    /// sin/cos evaluations (a shared `sin_cos` counts once).
    pub sincos: usize,
    /// Negations.
    pub neg: usize,
    /// abs/min/max/select.
    pub other: usize,
    /// `let` temporaries.
    pub temporaries: usize,
}

impl OpCounts {
    /// add + mul + div + sqrt + sin/cos + neg + other.
    pub fn total(&self) -> usize {
        self.add + self.mul + self.div + self.sqrt + self.sincos + self.neg + self.other
    }
}

/// Report line of one kernel.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct KernelReport {
    /// Kernel name.
    pub name: String,
    /// Operation counts.
    pub ops: OpCounts,
}

/// Report of one `generate` call.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Report {
    /// Scene name.
    pub scene: String,
    /// Number of joints.
    pub nq: usize,
    /// Runtime parameter names.
    pub params: Vec<String>,
    /// Nodes in the shared expression graph.
    pub graph_nodes: usize,
    /// One line per kernel, in emission order.
    pub kernels: Vec<KernelReport>,
    /// Wall-clock generation time (s), graph construction to formatted code.
    pub seconds: f64,
    /// Size of the generated code (bytes).
    pub code_bytes: usize,
    /// The scene's warnings ([`crate::spec::Scene::warnings`]: accepted but physically doubtful
    /// values), printed after the table.
    pub warnings: Vec<String>,
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "scene `{}`: NQ = {}, {} runtime parameter(s){}",
            self.scene,
            self.nq,
            self.params.len(),
            if self.params.is_empty() {
                String::new()
            } else {
                format!(" ({})", self.params.join(", "))
            }
        )?;
        writeln!(
            f,
            "{:<16} {:>7} {:>7} {:>5} {:>5} {:>7} {:>5} {:>6} {:>7} {:>6}",
            "kernel", "add", "mul", "div", "sqrt", "sin/cos", "neg", "other", "total", "temps"
        )?;
        for k in &self.kernels {
            let o = &k.ops;
            writeln!(
                f,
                "{:<16} {:>7} {:>7} {:>5} {:>5} {:>7} {:>5} {:>6} {:>7} {:>6}",
                k.name,
                o.add,
                o.mul,
                o.div,
                o.sqrt,
                o.sincos,
                o.neg,
                o.other,
                o.total(),
                o.temporaries
            )?;
        }
        write!(
            f,
            "graph: {} nodes; code: {} bytes; generated in {:.1} ms",
            self.graph_nodes,
            self.code_bytes,
            self.seconds * 1e3
        )?;
        for w in &self.warnings {
            write!(f, "\nwarning: {w}")?;
        }
        Ok(())
    }
}
