//! Ball-and-finger problems: derivative checks of the assembled NLPs, solves from the default
//! guess, KKT residuals, re-integration, refinement, and the Sect. 6.1 qualitative results.

use bf_optim::ipm::{Nlp, check_derivatives};
use bf_optim::ocp::Scheme;
use bf_optim::problems::{ProblemSettings, build, solve};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn settings(points: usize) -> ProblemSettings {
    ProblemSettings {
        points,
        ..ProblemSettings::default()
    }
}

#[test]
fn nlp_derivatives_match_finite_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for name in ["periodic-qc", "periodic-cot", "reach", "reorient"] {
        for scheme in [Scheme::Lg, Scheme::Radau { elements: 2 }] {
            let s = ProblemSettings {
                points: 4,
                scheme,
                impulse_cone: true,
                hdot_margin: Some(0.01),
                ..ProblemSettings::default()
            };
            let p = build(name, &s).unwrap();
            let n = p.nlp.num_variables();
            let m = p.nlp.num_constraints();
            let mut x = p.nlp.initial().to_vec();
            for v in x.iter_mut() {
                *v += rng.random_range(-0.3..0.3);
            }
            for l in &p.nlp.phases {
                x[l.t] = rng.random_range(0.5..1.5);
            }
            x[p.nlp.c0 + 1] = rng.random_range(1.0..2.0);
            let lam: Vec<f64> = (0..m).map(|_| rng.random_range(-1.0..1.0)).collect();
            let rep = check_derivatives(&p.nlp, &x, 0.5, &lam, 1e-6);
            assert!(rep.max_error() < 1e-5, "{name} {scheme:?} n={n}: {rep:?}");
        }
    }
}

#[test]
#[ignore = "exploration"]
fn explore() {
    let name = std::env::var("BF_PROBLEM").unwrap_or("periodic-qc".into());
    let pts: usize = std::env::var("BF_POINTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(30);
    let mut s = ProblemSettings {
        print_level: 1,
        ..settings(pts)
    };
    if let Ok(w) = std::env::var("BF_WARM") {
        s.warm_start =
            Some(bf_optim::problems::OcpSolution::read_json(std::path::Path::new(&w)).unwrap());
    }
    if std::env::var("BF_RADAU").is_ok() {
        s.scheme = Scheme::Radau { elements: 3 };
    }
    if let Ok(g) = std::env::var("BF_GUESS") {
        s.guess = if g == "contact" {
            bf_optim::problems::GuessKind::Contact
        } else {
            bf_optim::problems::GuessKind::Paper
        };
    }
    if let Ok(it) = std::env::var("BF_ITER") {
        s.max_iter = it.parse().unwrap();
    }
    let mut ipm = bf_optim::ipm::Settings {
        tol: 1e-8,
        ..Default::default()
    };
    if std::env::var("BF_ADAPTIVE").is_ok() {
        ipm.mu_strategy = bf_optim::ipm::MuStrategy::Adaptive;
    }
    if let Ok(w) = std::env::var("BF_MUINIT") {
        ipm.mu_init = w.parse().unwrap();
    }
    s.ipm = Some(ipm);
    let p = build(&name, &s).unwrap();
    let (v, r) = p.nlp.max_violation(p.nlp.initial());
    println!("initial violation {v} at row {r} ({})", p.nlp.row_name(r));
    let t = std::time::Instant::now();
    let sol = solve(&p, None).unwrap();
    println!(
        "{name}: {:?} obj {} period {} durations {:?} mean ω {:?} iters {} stages {:?} {:.1}s",
        sol.status,
        sol.objective,
        sol.period,
        sol.phase_durations,
        sol.mean_omega,
        sol.iterations,
        sol.stages,
        t.elapsed().as_secs_f64()
    );
    sol.write_json(std::path::Path::new(
        &std::env::var("BF_OUT").unwrap_or(format!("/tmp/{name}.json")),
    ))
    .unwrap();
}
