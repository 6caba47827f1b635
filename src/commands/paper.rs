//! `ball-finger paper [--out DIR] [--quick | --search]`: the paper's study (Sect. 6) end to
//! end, as far as the pipeline exists today. Every number in the report is computed in this
//! run (the optima of Sect. 6.1 and the plans of the closed loop are the global search's,
//! stored and solved again here unless `--search` runs the searches, decision record 0041);
//! the parts not implemented yet are listed as such (no placeholder numbers).
//!
//! Stages: (1) code generation for every built-in scene with op counts and timing (replaces the
//! Maple step, Sect. 5); (2) kernel verification at sample states: compiled kernels against the
//! generator's interpreter, and the invariants M = Mᵀ ≻ 0 (eq. 22a) and Ṁ − 2C skew-symmetric
//! (eq. 76 with Christoffel symbols); ... (8) the Appendix A/B check of `verify appendix`, computed
//! in the run (docs/appendix-errata.md explains each misprint).
//!
//! `--out` is one output set (`bf_output::OutputDir`): every stage writes into a private staging
//! directory, which replaces `--out` as a whole when the report is complete. A run whose checks
//! fail (a scenario failed or unverified, a plan not executed, a failed probe) still replaces
//! it, marked FAILED, and exits 1; a run that stops on an error leaves the previous report
//! untouched.

use crate::cli::PaperArgs;
use anyhow::{Context, Result, bail};
use bf_output::{DirSpec, Outcome, OutputDir};
use indicatif::{ProgressBar, ProgressStyle};
use std::fmt::Write as _;

/// The built-in scenes: (name, scene source compiled into `bf-generated`).
pub const BUILTIN_SCENES: [(&str, &str); 4] = [
    ("paper", bf_generated::paper::SCENE_TOML),
    ("human", bf_generated::human::SCENE_TOML),
    ("puma560", bf_generated::puma560::SCENE_TOML),
    ("iiwa7", bf_generated::iiwa7::SCENE_TOML),
];

fn stage(len: u64, msg: &str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    pb.set_style(
        ProgressStyle::with_template("{msg:<40} [{bar:30}] {pos}/{len} {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    pb.set_message(msg.to_string());
    pb
}

/// The optimum `paper` presents for `problem` posed with `settings`: with `--quick` the cold
/// solve `strategy` is; with `--search` `optimize`'s default global search; otherwise the
/// stored optimum of that search ([`crate::paper::stored`]) solved again from its own point.
fn presented_optimum(
    args: &PaperArgs,
    problem: bf_problem::Problem,
    settings: bf_problem::ProblemSettings,
    strategy: crate::pipeline::strategy::Strategy,
) -> Result<(bf_problem::BuiltProblem, bf_problem::OcpSolution)> {
    if args.quick {
        return super::optimize::solve_with_progress(problem, settings, strategy);
    }
    if args.search {
        return super::optimize::solve_globally_with_progress(problem, settings, strategy);
    }
    let stored = crate::paper::stored::stored_optimum(
        problem,
        Some(settings.impact_law.name()),
        settings.min_stick,
        settings.impulse_cone,
    )
    .with_context(|| {
        format!(
            "no stored optimum of {problem} with --min-stick {} (data/optima/); \
                 `paper --search` runs the search",
            settings.min_stick
        )
    })?;
    let pb = stage(1, &format!("{problem}: stored optimum"));
    let out = stored
        .resolve()
        .with_context(|| format!("the stored optimum {}", stored.path().display()))?;
    pb.inc(1);
    pb.finish();
    Ok(out)
}

/// Push the headings of an embedded markdown document one level down, so it nests under the
/// report's own section heading.
fn demote(md: &str) -> String {
    md.lines()
        .map(|l| {
            if l.starts_with('#') {
                format!("#{l}")
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Periods of the closed-loop comparison for the COT optima (10 s periods), as many as for the
/// QC optimum (0.6 s): stage 5, open and closed loop of every optimum, takes about 5 s.
const CLOSED_LOOP_COT_PERIODS: usize = 20;

/// Periods of the report's robustness tables: the 4th to the 10th decide the target.
const ROBUSTNESS_PERIODS: usize = 10;

/// Scenario name (directory, figure stem) of `problem`'s plan for the plant (Newton's impact
/// law) in the closed-loop section.
fn plan_dir(problem: bf_problem::Problem) -> String {
    format!("{}-newton", problem.name())
}

/// The closed-loop section's plan of `problem`: what `optimize --problem P` plans by default
/// for the plant that executes it (decision record 0040: Newton's impact law, eq. 39, a torque
/// margin and an approach clearance), the stored optimum of that search re-solved
/// ([`crate::paper::stored`]) or, with `--search`, the search itself; verified, written to
/// `DIR/P-newton/`, executed by every controller
/// ([`crate::paper::closed_loop::comparison_markdown`]) and against perturbed plants.
/// `sticking` is the problem's sticking optimum above, for comparison. The plan's failure and
/// flag go to `verdict` ([`RunVerdict::judge`]).
fn plan_markdown(
    args: &PaperArgs,
    problem: bf_problem::Problem,
    sticking: &bf_problem::OcpSolution,
    periods: usize,
    dir: &std::path::Path,
    verdict: &mut RunVerdict,
) -> Result<String> {
    let name = plan_dir(problem);
    // The paper's problems are posed on its compiled scenes: 3 joints, a ball of 1 m.
    let gap = bf_control::HybridGains::default().clearance.gap;
    let plan = super::optimize::PlanFor::of(problem, 3, gap, None, None, None)?;
    let (built, mut sol) = if args.search {
        let settings = plan.apply(bf_problem::ProblemSettings::default());
        let strategy = crate::pipeline::strategy::default_strategy(problem, settings.scheme);
        super::optimize::solve_globally_with_progress(problem, settings, strategy)?
    } else {
        let stored = crate::paper::stored::plan_for_the_plant(problem)
            .with_context(|| format!("no stored plan of {problem} (data/optima/)"))?;
        stored
            .resolve()
            .with_context(|| format!("the stored plan {}", stored.path().display()))?
    };
    sol.verification = crate::pipeline::verify::verify(&built, &sol, 1e-10).ok();
    let active = crate::pipeline::bounds::active_bounds(&built.ocp, &sol);
    sol.active_bounds = Some(active.clone());
    crate::pipeline::solution_io::write_solution(&sol, &dir.join(&name))?;
    crate::paper::scenarios::write_animation(&name, &built, &sol, dir)?;
    let verified = crate::pipeline::verify::is_verified(&sol);
    let stick = sol.stick_duration().unwrap_or(f64::NAN);
    let active = if active.is_empty() {
        "none".to_string()
    } else {
        active
            .iter()
            .map(|a| a.describe())
            .collect::<Vec<_>>()
            .join("; ")
    };
    let head = format!(
        "**`{problem}` planned for the plant.** The plan `optimize --problem {problem}` makes \
         by default (decision record 0040): Newton's law at the impact (eq. 39: ω unchanged, \
         the finger's joint velocity after the impact the one Newton's law gives), torques \
         within {:.0} % of their limits and an approach that keeps {:.0} mm from the ball until \
         its last 1 %, so that the plant's impact and the controller's feedback have what the \
         plan assumes; found by the same global search ({}): {} after {} iterations, J = {:.6} \
         (sticking optimum above {:.6}), stick phase {:.3} s, {}; active bounds (as in \
         section 4): {active}. Solution: \
         `{name}/solution.json`; animation of one period: \
         [animation_{name}.html](animation_{name}.html).\n",
        100.0 * (1.0 - plan.torque_margin),
        1e3 * plan.approach_clearance,
        if args.search {
            "run here"
        } else {
            "its stored optimum, solved again here"
        },
        crate::names::name(&sol.status),
        sol.iterations,
        sol.objective,
        sticking.objective,
        stick,
        if verified {
            "verified"
        } else {
            "**unverified**"
        },
    );
    let figures = dir.join("figures");
    let table =
        crate::paper::closed_loop::comparison_markdown(&name, &sol, periods, Some(&figures))?;
    // Against the perturbed plants, 10 periods each to keep the report's time (the COT plan's
    // 10 s periods make it the longer run, about 2 s per plant).
    let robustness =
        crate::paper::closed_loop::robustness_markdown(&name, &sol, ROBUSTNESS_PERIODS)?;
    verdict.plans += 1;
    verdict.judge(&format!("the plan of `{problem}`"), &sol);
    Ok(format!("{head}\n{table}\n{robustness}"))
}

/// A variant of `problem`'s scenario, the report's part `label`, posed with `settings` (their
/// mesh and strategy set here as for the scenarios: 20 points and a direct solve with
/// `--quick`, otherwise 30 points and the default strategy) and written under `dir`; judged
/// into `verdict` ([`RunVerdict::judge`]). A variant that could not be solved is, like a
/// failed scenario of the main table, a line of `report` and a failure of the run, and `None`:
/// the report goes on.
fn scenario_variant(
    label: &str,
    problem: bf_problem::Problem,
    settings: bf_problem::ProblemSettings,
    dir: &std::path::Path,
    (args, mu_s, presented): (&PaperArgs, f64, crate::paper::scenarios::Solver<'_>),
    report: &mut String,
    verdict: &mut RunVerdict,
) -> Result<Option<crate::paper::scenarios::ScenarioResult>> {
    let settings = bf_problem::ProblemSettings {
        points: if args.quick { 20 } else { 30 },
        ..settings
    };
    let strategy = if args.quick {
        crate::pipeline::strategy::Strategy::Direct
    } else {
        crate::pipeline::strategy::default_strategy(problem, settings.scheme)
    };
    match crate::paper::scenarios::run_scenario(
        problem.name(),
        settings,
        strategy,
        dir,
        mu_s,
        presented,
    ) {
        Ok(r) => {
            verdict.judge(label, &r.solution);
            Ok(Some(r))
        }
        Err(e) => {
            let line = format!("{label} failed: {}", crate::errors::render(&e));
            writeln!(report, "{line}\n")?;
            verdict.failures.push(line);
            Ok(None)
        }
    }
}

/// The report's section on the impulse cone (eq. 66, Sect. 7): the planned impulses of the
/// Sect. 6.1 scenarios and of COT with the cone imposed (`coned`, written under
/// [`crate::paper::report::impulse_cone::CONE_DIR`], `how` saying how it was found), the QC
/// sentence and the COT comparison.
fn impulse_cone_section(
    results: &[crate::paper::scenarios::ScenarioResult],
    cot: &crate::paper::scenarios::ScenarioResult,
    coned: &crate::paper::scenarios::ScenarioResult,
    mu_s: f64,
    how: &str,
) -> String {
    use crate::paper::report::impulse_cone::{
        CONE_DIR, CotFacts, comparison, cone_table, first_impact, qc_sentence,
    };
    let mut rows: Vec<(String, &bf_problem::OcpSolution)> = results
        .iter()
        .map(|r| (format!("`{}`", r.name), &r.solution))
        .collect();
    rows.push((
        format!("`periodic-cot`, cone imposed (`{CONE_DIR}/`)"),
        &coned.solution,
    ));
    let mut s = format!(
        "### The impulse friction cone at the impact (Sect. 7, eq. 66)\n\n\
         The sticking impact law (eq. 40) gives the finger whatever impulse ι stops the contact \
         point; the problems of Sect. 6.1 do not ask whether static friction can hold it, \
         ‖ι_∥‖ ≤ μ_s ι·n (eq. 66), which the paper discusses as an option in Sect. 7 \
         (`optimize --impulse-cone`). Each optimum's planned impulse against the cone, from the \
         re-integration's records (`verification.impacts` in its `solution.json`; ⚑: a real \
         contact would slip at the impact, which the plan assumes it does not):\n\n{}\n",
        cone_table(&rows, mu_s)
    );
    if let Some(qc) = results
        .iter()
        .find(|r| r.name == "periodic-qc")
        .and_then(|r| first_impact(&r.solution))
    {
        s += &format!("{}\n\n", qc_sentence(qc, mu_s));
    }
    match (CotFacts::of(&cot.solution), CotFacts::of(&coned.solution)) {
        (Some(free), Some(imposed)) => {
            s += &format!(
                "COT with the cone imposed, {how} ({}):\n\n{}\n",
                if crate::pipeline::verify::is_verified(&coned.solution) {
                    "verified"
                } else {
                    "**unverified**"
                },
                comparison(&free, &imposed, mu_s)
            );
        }
        _ => s += "COT with the cone imposed: no re-integrated impact to compare.\n",
    }
    s
}

/// The flag of an optimum whose planned impact needs more static friction than μ_s, its problem
/// leaving the cone of eq. 66 out ([`crate::pipeline::verify::impulse_cone_warning`]): a result
/// of the run, counted in the summary, not a failure (the paper's problems leave the cone out).
fn impulse_flag(label: &str, sol: &bf_problem::OcpSolution) -> Option<String> {
    sol.verification
        .as_ref()
        .and_then(crate::pipeline::verify::impulse_cone_warning)
        .map(|w| format!("{label}: {w}"))
}

/// Why the optimum `sol` does not count as a result: the solver did not converge, or its
/// re-integration failed the verification or could not run.
fn optimum_failure(sol: &bf_problem::OcpSolution) -> Option<String> {
    super::optimize::failure_of(sol).or_else(|| {
        sol.verification
            .is_none()
            .then(|| "the optimum could not be re-integrated, so it is unverified".to_string())
    })
}

/// What decides a run's outcome: the checks that failed (a scenario that could not be solved
/// or is unverified, a plan that could not be made, verified or executed, a stability probe
/// that failed), which mark the set FAILED and exit 1, and the measurements flagged beyond
/// their bounds, which are results of the run, counted in the summary.
#[derive(Debug, Default)]
pub struct RunVerdict {
    /// Failed checks, one sentence each.
    pub failures: Vec<String>,
    /// Flagged measurements, one sentence each.
    pub flags: Vec<String>,
    /// Plans for the plant made in the run (none with `--quick`): the summary says they were
    /// executed only when there were some.
    pub plans: usize,
}

impl RunVerdict {
    /// The report's summary section: the failed checks first (the run is FAILED), then the
    /// flagged measurements.
    pub fn summary_markdown(&self) -> String {
        let mut s = String::from("## Summary\n\n");
        if self.failures.is_empty() {
            s.push_str(if self.plans > 0 {
                "Every scenario and plan was solved and verified, every plan executed, every \
                 stability probe returned a finite number or a clear error.\n\n"
            } else {
                "Every scenario was solved and verified (this run made no plan for the plant), \
                 every stability probe returned a finite number or a clear error.\n\n"
            });
        } else {
            let _ = writeln!(
                s,
                "**FAILED**: {} check{} failed (the set is marked by its `FAILED` file):\n",
                self.failures.len(),
                if self.failures.len() == 1 { "" } else { "s" }
            );
            for f in &self.failures {
                let _ = writeln!(s, "- {f}");
            }
            s.push('\n');
        }
        if self.flags.is_empty() {
            s.push_str("No measurement is flagged beyond its bound.\n\n");
        } else {
            s.push_str(
                "Flagged measurements (results of this run beyond a bound they are judged on, \
                 not failures of the run):\n\n",
            );
            for f in &self.flags {
                let _ = writeln!(s, "- {f}");
            }
            s.push('\n');
        }
        s
    }

    /// Adds what the optimum `sol` of the part `label` gives the verdict: its failure (not
    /// solved, or unverified) and its flag (an impact that needs more static friction than
    /// μ_s, where its problem leaves the impulse cone out).
    pub fn judge(&mut self, label: &str, sol: &bf_problem::OcpSolution) {
        self.failures
            .extend(optimum_failure(sol).map(|why| format!("{label}: {why}")));
        self.flags.extend(impulse_flag(label, sol));
    }

    /// The error the set is marked FAILED with, if a check failed.
    pub fn failure(&self) -> Option<String> {
        (!self.failures.is_empty()).then(|| {
            format!(
                "{} check{} of the paper run failed: {}",
                self.failures.len(),
                if self.failures.len() == 1 { "" } else { "s" },
                self.failures.join("; ")
            )
        })
    }
}

/// Appends the report section `md` to `report`, or, where it could not be made, one line
/// `failed: why` in its place (the report goes on with its other sections) and that line to
/// `failures`.
fn section(
    report: &mut String,
    md: Result<String>,
    failed: &str,
    failures: &mut Vec<String>,
) -> std::fmt::Result {
    match md {
        Ok(md) => writeln!(report, "{md}"),
        Err(e) => {
            let line = format!("{failed}: {}", crate::errors::render(&e));
            writeln!(report, "{line}\n")?;
            failures.push(line);
            Ok(())
        }
    }
}

/// The output directory of `paper`.
pub const OUTPUT_DIR: DirSpec<'static> = DirSpec {
    option: "--out",
    command: "paper",
};

/// The code-generation table of the report (scene, joints, kernels, graph nodes, code bytes,
/// generation time) and the per-scene generator reports, for `scenes` = (name, TOML source).
/// Each scene is generated as `generate` emits it ([`super::generate::generate_module`]), so
/// the table counts the same kernels. `tick` is called after each scene, `warn` with each of a
/// scene's warnings.
pub fn codegen_table(
    scenes: &[(&str, &str)],
    tick: &dyn Fn(),
    warn: &dyn Fn(String),
) -> Result<(String, String)> {
    let mut table = String::from(
        "| scene | joints | kernels | graph nodes | code bytes | generation time |\n|---|---|---|---|---|---|\n",
    );
    let mut details = String::new();
    for &(name, text) in scenes {
        let scene = bf_codegen::Scene::from_toml_str(text, &format!("scenes/{name}.toml"))?;
        // As for every scene a command loads (`load_scene`): accepted but doubtful values.
        for w in scene.warnings() {
            warn(format!("warning: scenes/{name}.toml: {w}"));
        }
        // The module `generate` emits (same kernel list), with the default options.
        let g = super::generate::generate_module(&scene, text, &Default::default())
            .with_context(|| format!("generating scene {name}"))?;
        let r = &g.report;
        writeln!(
            table,
            "| {name} | {} | {} | {} | {} | {:.1} ms |",
            r.nq,
            r.kernels.len(),
            r.graph_nodes,
            r.code_bytes,
            r.seconds * 1e3
        )?;
        writeln!(details, "### Scene `{name}`\n\n```text\n{r}\n```\n")?;
        tick();
    }
    Ok((table, details))
}

/// Run `paper`.
pub fn run(args: &PaperArgs) -> Result<()> {
    let mut out = OutputDir::create(&args.out, &OUTPUT_DIR, &[])?;
    let dir = out.path().to_path_buf();
    // CI logs (stderr not a terminal) get a line per stage and one every 5 s.
    let hb = crate::progress::Heartbeat::start("paper");
    // The sections; the title and the summary, which needs all of them, go before them at
    // the end.
    let mut report = String::new();
    let mut verdict = RunVerdict::default();

    // Stage 1: generation.
    hb.stage("1/8 code generation");
    writeln!(
        report,
        "## 1. Code generation (replaces the Maple step of Sect. 5)\n"
    )?;
    let pb = stage(BUILTIN_SCENES.len() as u64, "generating kernels");
    let (table, details) = codegen_table(&BUILTIN_SCENES, &|| pb.inc(1), &|w| {
        pb.suspend(|| crate::errln!("{w}"))
    })?;
    pb.finish();
    writeln!(report, "{table}\n{details}")?;

    writeln!(report, "### Model only what a scene requires\n")?;
    writeln!(
        report,
        "{}",
        super::requires::markdown(&super::requires::variants()?)?
    )?;

    // Stage 2: verification at sample states.
    hb.stage("2/8 kernel verification");
    writeln!(report, "## 2. Kernel verification at sample states\n")?;
    let n_states = if args.quick { 4 } else { 32 };
    let pb = stage(n_states as u64, "verifying kernels");
    let v = super::verify::verify_paper_scene(n_states, || pb.inc(1))?;
    pb.finish();
    writeln!(report, "{v}")?;

    // Stage 3: Fig. 4, the smooth saturation of Sect. 4.3.
    hb.stage("3/8 smooth saturation");
    writeln!(report, "## 3. Smooth saturation (Sect. 4.3, Fig. 4)\n")?;
    let fig_dir = dir.join("figures");
    let fig4 = bf_plot::sat::fig4_saturation(&[0.01, 0.1], 801);
    bf_plot::render(&fig4, fig_dir.join("fig4_saturation"))?;
    let worst: f64 = (0..=2000)
        .map(|i| -1.5 + 2.0 * i as f64 / 2000.0)
        .map(|x| {
            (bf_plot::sat::sat_smooth(x, -1.0, 0.0, 0.01) - bf_plot::sat::sat_exact(x, -1.0, 0.0))
                .abs()
        })
        .fold(0.0, f64::max);
    writeln!(
        report,
        "![Fig. 4 counterpart: exact vs smooth saturation](figures/fig4_saturation.svg)\n\n\
         With ε = 0.01 the smooth saturation (eq. 58–59) differs from the exact one by at most \
         {worst:.2e} (at the corners x = −1 and x = 0; the figure shows, as the paper's \
         Fig. 4 does, the quadrant around the symmetry point, with the corner at 0), which \
         agrees with the paper's remark that the two are hardly distinguishable.\n"
    )?;

    // Stage 4: the optimal-control scenarios of Sect. 6.1.
    hb.stage("4/8 optimal periodic rotations");
    writeln!(report, "## 4. Optimal periodic rotations (Sect. 6.1)\n")?;
    let paper_scene =
        bf_codegen::Scene::from_toml_str(bf_generated::paper::SCENE_TOML, "scenes/paper.toml")?;
    let mu_s = paper_scene.friction.as_ref().map_or(0.8, |f| f.mu_s);
    writeln!(
        report,
        "Three phases (free, stick, free), periodic, {} collocation points per phase to start \
         with (hp Legendre–Gauss–Radau, 3 elements; the table gives the mesh each optimum \
         ends on), ε = 0.01, |τ| ≤ 1 N m, h(0) ≥ 0.3 r. The COT period \
         is bounded by {} s (COT lets the finger rest at no cost). The problems have many local \
         optima (`ball-finger report strategies` compares cold start, continuation, multi-start \
         and the global search). Strategy: {} Every solution is verified by re-integrating each \
         collocation element from its collocated start state with the optimal torques (DOPRI5, \
         rtol 1e-10; the largest state error at the element ends is the \"re-integration \
         defect\", which measures the discretisation error; docs/decisions/0005); an optimum \
         whose defect exceeds {:e} is hp-refined until it passes, and one that still fails is \
         marked **unverified**, and so is every claim below that rests on it. Solutions: \
         `<scenario>/solution.json`, torques: `<scenario>/torques.csv`.\n",
        if args.quick { 20 } else { 30 },
        bf_problem::COT_MAX_PERIOD,
        if args.quick {
            "one cold solve per problem (`--quick`).".to_string()
        } else {
            format!(
                "the default search of `optimize --impact-law stick` (the paper's sticking \
                 problem; `optimize` plans for a Newton plant by default, decision record \
                 0040): {} on a coarse mesh for every periodic problem (for periodic-qc every \
                 start first bounds the stick phase to ≥ 0.1 s, then relaxes it to 0.01 s), \
                 then reshaping moves, basin hops and polishing, the best optima re-solved on \
                 the problem's mesh (each from a warm and from a close barrier start, the lower \
                 kept; more of them while a coarse objective is below the best re-solved one), \
                 re-integrated and hp-refined until one verifies, then the \
                 moves and hops again around the verified winner on its own mesh (see \
                 ball_finger::pipeline::global and docs/optima.md). {}",
                crate::pipeline::strategy::default_strategy(
                    bf_problem::Problem::PeriodicQc,
                    bf_problem::ProblemSettings::default().scheme
                ),
                if args.search {
                    "The searches ran in this run (`--search`)."
                } else {
                    "The searches' optima (seed 0) are stored in the repository \
                     (`data/optima/`, with the command that produced each) and were solved \
                     again here, warm from their own primal-dual points on their own meshes, \
                     and re-integrated like any optimum: a stored optimum that this program no \
                     longer reproduces is marked unverified below. `paper --search` runs the \
                     searches instead (seven searches, about four to seven more minutes on 2 cores; \
                     decision record 0041)."
                }
            )
        },
        crate::pipeline::verify::VERIFIED_DEFECT
    )?;
    let presented =
        |problem, settings, strategy| presented_optimum(args, problem, settings, strategy);
    let (results, failures) = crate::paper::scenarios::run_all(&dir, args.quick, mu_s, &presented)?;
    writeln!(
        report,
        "{}",
        crate::paper::scenarios::results_markdown(&results)?
    )?;
    if !failures.is_empty() {
        writeln!(report, "Scenarios that failed:\n")?;
        for f in &failures {
            writeln!(report, "- {f}")?;
        }
        writeln!(report)?;
        verdict
            .failures
            .extend(failures.iter().map(|f| format!("scenario {f}")));
    }
    for r in &results {
        verdict.judge(&format!("scenario `{}`", r.name), &r.solution);
    }
    for r in &results {
        writeln!(
            report,
            "### {}\n\n{}",
            r.name,
            crate::paper::scenarios::figures_markdown(&r.name)
        )?;
        let resolved = !args.quick && !args.search;
        if let (Some(st), Some(stages)) = (
            &r.solution.strategy,
            crate::paper::scenarios::solve_stages(&r.solution, resolved),
        ) {
            writeln!(
                report,
                "Solve stages (the search's summary, which counts every solve and iteration \
                 of the table; the kept chain's solves and the hp refinements that the \
                 verification ran on it, each from the mesh the one before it ended on; \
                 indented, the rounds of the last refinement (or of the refinement its mesh \
                 comes from, marked as such, where the winner inherited it from a hop's \
                 origin); and last the optimum of the table above where \
                 it is another solve; every stage is in `{}/solution.json`):\n\n```text\n{stages}```\n",
                r.name,
            )?;
            if let Some(line) = crate::pipeline::search::basin_line(st) {
                writeln!(report, "Global search, {line}.\n")?;
            }
        }
        if let Some(v) = &r.solution.verification {
            writeln!(
                report,
                "Verification:\n\n```text\n{}\n```\n",
                v.summary().trim_end()
            )?;
        }
    }

    // QC again with the longer minimum stick duration, by the same strategy as above.
    if let Some(short) = results.iter().find(|r| r.name == "periodic-qc") {
        use crate::paper::report::min_stick::{LONG_DIR, LONG_MIN_STICK, StickRun};
        let long = scenario_variant(
            &format!("QC with `--min-stick {LONG_MIN_STICK}`"),
            bf_problem::Problem::PeriodicQc,
            bf_problem::ProblemSettings {
                min_stick: LONG_MIN_STICK,
                ..bf_problem::ProblemSettings::default()
            },
            &dir.join(LONG_DIR),
            (args, mu_s, &presented),
            &mut report,
            &mut verdict,
        )?;
        if let Some(long) = long {
            let runs = [
                StickRun {
                    min_stick: bf_problem::ProblemSettings::default().min_stick,
                    result: short.clone(),
                    prefix: String::new(),
                },
                StickRun {
                    min_stick: LONG_MIN_STICK,
                    result: long,
                    prefix: LONG_DIR.to_string(),
                },
            ];
            writeln!(
                report,
                "{}",
                crate::paper::report::min_stick::markdown(&runs, &|r| {
                    crate::paper::scenarios::results_markdown(r)
                })?
            )?;
        }
    }

    // COT again with the impulse cone of eq. 66 imposed (Sect. 7), by the same strategy.
    if let Some(cot) = results.iter().find(|r| r.name == "periodic-cot") {
        let coned = scenario_variant(
            "COT with `--impulse-cone`",
            bf_problem::Problem::PeriodicCot,
            bf_problem::ProblemSettings {
                impulse_cone: true,
                // `--quick`'s cold solves land in other optima than the searches; from the
                // COT optimum above, the cone's own effect on it is what the section shows.
                warm_start: args.quick.then(|| cot.solution.clone()),
                ..bf_problem::ProblemSettings::default()
            },
            &dir.join(crate::paper::report::impulse_cone::CONE_DIR),
            (args, mu_s, &presented),
            &mut report,
            &mut verdict,
        )?;
        if let Some(coned) = coned {
            writeln!(
                report,
                "{}",
                impulse_cone_section(
                    &results,
                    cot,
                    &coned,
                    mu_s,
                    if args.quick {
                        "solved warm from the COT optimum above (`--quick`)"
                    } else {
                        "found by the same strategy as the table above"
                    }
                )
            )?;
        }
    }

    if let Some(md) = crate::paper::scenarios::fig11_compare_paths(&dir, &results)? {
        writeln!(report, "{md}")?;
    }

    // Stage 5: open-loop simulation of the COT torques (Sect. 6.2).
    hb.stage("5/8 open-loop simulation");
    writeln!(report, "## 5. Open-loop simulation with slip (Sect. 6.2)\n")?;
    match results.iter().find(|r| r.name == "periodic-cot") {
        Some(cot) => {
            let periods = if args.quick { 1 } else { 3 };
            let pb = stage(1, "open-loop simulation");
            let (o, tracked) = crate::paper::openloop::run_open_loop_study(
                &cot.solution,
                periods,
                &[
                    crate::paper::openloop::DEFAULT_PD_TRACK,
                    crate::paper::openloop::PdTrack {
                        during_contact: true,
                        ..crate::paper::openloop::DEFAULT_PD_TRACK
                    },
                ],
                &dir,
            )?;
            pb.finish();
            let runs = std::iter::once(("open loop".to_string(), &o)).chain(
                tracked
                    .iter()
                    .map(|t| (t.feedback.map_or(String::new(), |pd| pd.label()), t)),
            );
            // A failed energy-balance check is a failed check of the run (its figures rest on
            // an integration that did not balance); the other warnings are measurements of
            // the model, flagged.
            for (name, run) in runs {
                for (failed_check, line) in run.warning_lines() {
                    let line = format!("section 5, {name}: {line}");
                    if failed_check {
                        verdict.failures.push(line);
                    } else {
                        verdict.flags.push(line);
                    }
                }
            }
            writeln!(
                report,
                "{}{}",
                crate::paper::openloop::markdown(&o)?,
                crate::paper::openloop::pd_markdown(&o, &tracked)?
            )?;
        }
        None => writeln!(
            report,
            "Not run: the `periodic-cot` scenario has no solution.\n"
        )?,
    }
    // The optima executed in closed loop beside the open loop and the PD (Sect. 6.2, 7).
    writeln!(
        report,
        "### Open loop, PD and hybrid control side by side\n\n\
         Each optimum executed from its own initial state on its own scene by the open loop \
         (τ*(t) repeated), the joint-space PD around the optimal trajectory in the free phases, \
         and bf-control's hybrid controller (computed torque in free motion, force/velocity \
         control in contact, timed by the contact events; `ball-finger track`). The ω error of \
         a period is ‖ω̄_k − ω̄*‖ / ‖ω̄*‖, a period runs from one impact to the next (a bounce, an \
         impact less than {} s after a lift-off, is part of its contact phase).\n",
        bf_control::MIN_FLIGHT
    )?;
    for r in &results {
        let periods = match (args.quick, r.name.as_str()) {
            (true, _) => 3,
            (false, "periodic-qc") => 20,
            (false, _) => CLOSED_LOOP_COT_PERIODS,
        };
        let pb = stage(1, "closed loop");
        let md = crate::paper::closed_loop::comparison_markdown(
            &r.name,
            &r.solution,
            periods,
            Some(&dir.join("figures")),
        );
        pb.finish();
        section(
            &mut report,
            md,
            &format!("`{}`: not executed", r.name),
            &mut verdict.failures,
        )?;
    }
    // The plans for the plant (eq. 39, decision records 0033, 0040) of the QC problem and the
    // human finger's COT problem: the hybrid controller cannot execute the sticking optima on
    // a Newton plant when their short stick phase spins the ball through the sticking
    // impact's impulse, which a Newton impact does not give, and it executes these. Not with
    // --quick (a smoke run).
    for (problem, periods) in [
        (bf_problem::Problem::PeriodicQc, 20),
        (
            bf_problem::Problem::PeriodicCotHuman,
            CLOSED_LOOP_COT_PERIODS,
        ),
    ] {
        if let Some(sticking) = results
            .iter()
            .find(|r| r.name == problem.name() && !args.quick)
        {
            let pb = stage(1, &format!("{problem}: plan for the plant"));
            let md = plan_markdown(
                args,
                problem,
                &sticking.solution,
                periods,
                &dir,
                &mut verdict,
            );
            pb.finish();
            section(
                &mut report,
                md,
                &format!("The plan of `{problem}` for the plant failed"),
                &mut verdict.failures,
            )?;
        }
    }

    // Stage 6: stability at the extremes.
    hb.stage("6/8 extremes");
    writeln!(report, "## 6. Stability at the extremes\n")?;
    let pb = stage(1, "extremes");
    let ext = crate::paper::extremes::run_extremes(args.quick)?;
    pb.finish();
    writeln!(report, "{}", ext.to_markdown())?;
    for f in ext.failures() {
        verdict.failures.push(format!(
            "stability probe {} / {} / {} failed (section 6)",
            f.case, f.parameter, f.quantity
        ));
    }
    let (exceeded, measures) = ext.flag_counts();
    if exceeded > 0 {
        verdict.flags.push(format!(
            "⚑ {exceeded} of {measures} error measures of the stability probes exceed their \
             flag bound (section 6): deliberate measurements of the methods at their extremes"
        ));
    }
    out.write(
        crate::paper::extremes::report::CSV_NAME,
        ext.to_csv().as_bytes(),
    )?;

    // Stage 7: the speed–accuracy trade, measured in this run.
    hb.stage("7/8 speed versus accuracy");
    writeln!(report, "## 7. Speed versus accuracy\n")?;
    // The mesh study also measures the discretisation error at the QC optimum presented above.
    let presented = results
        .iter()
        .find(|r| r.name == "periodic-qc")
        .map(|r| &r.solution);
    let sa = crate::paper::speed_accuracy::speed_accuracy(&dir, args.quick, presented)?;
    writeln!(report, "{}", demote(&sa))?;

    // Stage 8: appendix check.
    hb.stage("8/8 appendix check");
    writeln!(report, "## 8. Paper Appendix A/B: printed vs derived\n")?;
    let pb = stage(1, "appendix check");
    let entries = crate::paper::appendix::check_appendix()?;
    pb.finish();
    writeln!(
        report,
        "Output of `ball-finger verify appendix` in this run; docs/appendix-errata.md explains \
         each misprint.\n\n{}",
        crate::paper::appendix::markdown(&entries)?
    )?;

    writeln!(report, "## 9. Known limitations\n")?;
    // The scenarios' `--points` over 3 Radau elements, as the mesh rounds them.
    let per_element = bf_optim::ocp::mesh::MeshSpec::from_scheme(
        bf_optim::ocp::Scheme::Radau { elements: 3 },
        if args.quick { 20 } else { 30 },
    )?
    .degrees[0];
    let optima = if args.quick {
        "The optima shown are one cold solve per problem (`--quick`), not the default \
         search's optima, which a run without `--quick` presents."
    } else {
        "The optima shown are those `optimize`'s default global search verifies with seed 0: \
         verified local optima, not certified global ones. Over seeds 0–9 the searches of the \
         problems shown end within 0.3 % of each other; `optimize`'s default plan of \
         `periodic-cot` (not shown here) ends a few percent apart from seed to seed \
         (docs/optima.md gives the figures per problem and how to search further)."
    };
    writeln!(
        report,
        "- The scenarios above use hp Legendre–Gauss–Radau (3 elements of {per_element} \
         points per phase to start with, refined where an optimum's re-integration asks for it; \
         section 4 gives each optimum's mesh). Legendre–Gauss collocation, the paper's scheme \
         (`optimize --scheme lg`), solves the seven problems too, with other costs in time \
         (criterion figures for both schemes in BENCHMARKS.md, `cargo bench --bench \
         problems`), but with one polynomial per phase and no mesh refinement none of them \
         verifies at 30 points per phase (`periodic-qc` does from about 120).\n\
         - The unpivoted KKT factorization eliminates constraint rows before their variables; \
         where that misleads the inertia test the solver switches to 2 × 2 (variable, row) \
         pivots within the solve, and where the factor grows unstable it raises its static \
         dual regularization from 1e-9 to 3e-8 (optim/README.md, \
         BENCHMARKS.md for the mesh sweep).\n\
         - The periodic problems have many local optima; which one a solve reaches depends on \
         the strategy and on rounding (section 4 and `report strategies`). {optima}\n\
         - Each verification summary gives the open-loop drift: one phase replayed whole from \
         its collocated initial state (informative; the verdict re-integrates element by \
         element). Replayed over whole periods in the plant (Newton's law, slip), the optimal \
         torques leave the optimum within the first periods (section 5). Feedback executes \
         the plans for the plant; the sticking problems' optima assume an impact the plant \
         does not have (section 5, decision record 0040)."
    )?;

    let head = format!(
        "# ball-finger: reproduction of *Ball-and-finger system* (Sect. 6)\n\n\
         Generated by `ball-finger paper{}` ({}). Every number below was computed in this run.\n\n\
         {}",
        if args.quick { " --quick" } else { "" },
        env!("CARGO_PKG_VERSION"),
        verdict.summary_markdown()
    );
    out.write("report.md", format!("{head}{report}").as_bytes())?;
    let failure = verdict.failure();
    out.commit(match &failure {
        Some(f) => Outcome::Failed(f),
        None => Outcome::Success,
    })?;
    hb.stage("done");
    drop(hb);
    for f in &verdict.failures {
        crate::errln!("paper: FAILED: {f}");
    }
    for f in &verdict.flags {
        crate::errln!("paper: flagged: {f}");
    }
    crate::outln!("wrote {}", args.out.join("report.md").display())?;
    match failure {
        Some(_) => bail!(
            "{} check(s) of the paper run failed (listed above and at the top of {}); the set \
             is marked FAILED",
            verdict.failures.len(),
            args.out.join("report.md").display()
        ),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table counts every kernel `generate` emits: the scene's own list plus the
    /// inverse-dynamics family (for the paper scene 21, where the scene lists 16).
    #[test]
    fn codegen_table_counts_the_kernels_generate_emits() {
        let (table, details) = codegen_table(&BUILTIN_SCENES, &|| {}, &|_| {}).unwrap();
        for (name, text) in BUILTIN_SCENES {
            let scene = bf_codegen::Scene::from_toml_str(text, name).unwrap();
            let full = bf_codegen::kernels::with_robot_kernels(&scene).kernels;
            let row = table
                .lines()
                .find(|l| l.starts_with(&format!("| {name} |")))
                .unwrap();
            let count: usize = row.split('|').nth(3).unwrap().trim().parse().unwrap();
            assert_eq!(count, full.len(), "{name}: {row}");
            let code = generate_module_code(&scene, text);
            for k in &full {
                assert!(
                    code.contains(&format!("pub fn {k}(")),
                    "{name}: {k} not emitted"
                );
            }
        }
        assert!(details.contains("### Scene `paper`"));
        let paper = bf_codegen::Scene::from_toml_str(BUILTIN_SCENES[0].1, "paper").unwrap();
        assert!(
            bf_codegen::kernels::with_robot_kernels(&paper)
                .kernels
                .len()
                > paper.kernels.len()
        );
    }

    /// A run with a failed check says FAILED at the top of its summary, lists every reason and
    /// gives the set its error; flagged measurements are counted apart, and alone they do not
    /// fail the run.
    #[test]
    fn the_summary_lists_failed_checks_apart_from_flagged_measurements() {
        let flagged = RunVerdict {
            failures: vec![],
            flags: vec!["⚑ 5 of 75 error measures exceed their flag bound".into()],
            plans: 2,
        };
        assert_eq!(flagged.failure(), None);
        let md = flagged.summary_markdown();
        assert!(md.starts_with("## Summary\n"), "{md}");
        assert!(!md.contains("FAILED"), "{md}");
        assert!(md.contains("- ⚑ 5 of 75 error measures"), "{md}");
        assert!(md.contains("every plan executed"), "{md}");
        // A run without plans (`--quick`) does not claim to have executed any.
        let md = RunVerdict::default().summary_markdown();
        assert!(
            md.contains("made no plan") && !md.contains("plan executed"),
            "{md}"
        );

        let failed = RunVerdict {
            failures: vec![
                "scenario `periodic-qc` failed: no solution".into(),
                "the plan of `periodic-cot-human`: the solution is unverified".into(),
            ],
            flags: vec![],
            plans: 1,
        };
        let md = failed.summary_markdown();
        assert!(md.contains("**FAILED**: 2 checks failed"), "{md}");
        assert!(
            md.contains("- scenario `periodic-qc` failed: no solution\n"),
            "{md}"
        );
        assert!(md.contains("No measurement is flagged"), "{md}");
        let why = failed.failure().unwrap();
        assert!(
            why.starts_with("2 checks of the paper run failed: scenario `periodic-qc`"),
            "{why}"
        );
        assert!(why.contains("the plan of `periodic-cot-human`"), "{why}");
    }

    /// A presented optimum fails the run when it is unverified or was not re-integrated at all.
    #[test]
    fn an_unverified_or_unchecked_optimum_is_a_failure() {
        let stored =
            crate::paper::stored::sticking_optimum(bf_problem::Problem::PeriodicQc).unwrap();
        let sol = stored.solution().unwrap();
        assert!(crate::pipeline::verify::is_verified(&sol));
        assert_eq!(optimum_failure(&sol), None);
        let mut unverified = sol.clone();
        if let Some(v) = unverified.verification.as_mut() {
            v.max_defect = 1.0;
        }
        let why = optimum_failure(&unverified).unwrap();
        assert!(why.contains("unverified"), "{why}");
        let mut unchecked = sol;
        unchecked.verification = None;
        let why = optimum_failure(&unchecked).unwrap();
        assert!(why.contains("could not be re-integrated"), "{why}");
    }

    fn generate_module_code(scene: &bf_codegen::Scene, text: &str) -> String {
        super::super::generate::generate_module(scene, text, &Default::default())
            .unwrap()
            .code
    }
}
