//! `ball-finger report <which> --out DIR [--quick]`: stand-alone reports (issue 7). Writes
//! `DIR/<which>.md` and the figures under `DIR/figures/`.

use anyhow::{Context, Result, bail};

use crate::cli::ReportArgs;

/// Names of the reports `report` knows.
pub const REPORTS: &[&str] = &["speed-accuracy"];

/// Runs the report named by `a.which`.
pub fn run(a: &ReportArgs) -> Result<()> {
    let md = match a.which.as_str() {
        "speed-accuracy" => crate::report::speed_accuracy(&a.out, a.quick)?,
        other => bail!(
            "unknown report `{other}`; known reports: {}",
            REPORTS.join(", ")
        ),
    };
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let path = a.out.join(format!("{}.md", a.which));
    let text = format!("# ball-finger: {} report\n\n{md}", a.which);
    std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}
