//! `ball-finger report <which> --out DIR [--quick]`: stand-alone reports (issue 7). Writes
//! `DIR/<which>.md` and the figures under `DIR/figures/`.

use anyhow::{Context, Result, bail};

use crate::cli::ReportArgs;

/// Names of the reports `report` knows.
pub const REPORTS: &[&str] = &["speed-accuracy", "strategies"];

/// Runs the report named by `a.which`.
pub fn run(a: &ReportArgs) -> Result<()> {
    let md = match a.which.as_str() {
        "speed-accuracy" => crate::study::speed_accuracy::speed_accuracy(&a.out, a.quick)?,
        "strategies" => {
            let pb = super::optimize::iteration_spinner("strategies");
            pb.enable_steady_tick(std::time::Duration::from_millis(120));
            pb.set_message("solving ...");
            let md = crate::report::strategies_report(a.quick, &|r| {
                pb.println(format!(
                    "{} {}: {} phi {:.4e} in {:.1} s",
                    r.problem, r.strategy, r.status, r.objective, r.seconds
                ));
            })?;
            pb.finish_and_clear();
            md
        }
        other => bail!(
            "unknown report `{other}`; known reports: {}",
            REPORTS.join(", ")
        ),
    };
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let path = a.out.join(format!("{}.md", a.which));
    let text = format!("# ball-finger: {} report\n\n{md}", a.which);
    crate::io::write_atomic(&path, text.as_bytes())
        .with_context(|| format!("writing {}", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}
