//! The speed–accuracy report in quick mode: its numbers must behave as the
//! numerics say they must — errors fall as tolerances tighten and ε shrinks, f64 kernels agree
//! with double-double to a few ulps, f32 ones only to single precision, FMA is no less
//! accurate — and every linked figure exists.

#[path = "common/cli.rs"]
mod cli_util;

use ball_finger::paper::speed_accuracy::{SpeedAccuracy, VARIANT_KERNELS, VARIANTS};
use ball_finger::pipeline;
use bf_problem::{Problem, ProblemSettings};

#[test]
fn quick_report_is_consistent() {
    // The optimum a report presents: here `optimize --strategy direct`'s (Radau 3 × 10).
    let presented = {
        let settings = ProblemSettings {
            points: 30,
            ..ProblemSettings::default()
        };
        let p = pipeline::build(Problem::PeriodicQc, &settings).unwrap();
        pipeline::solve(&p, None).unwrap()
    };
    assert!(presented.status.is_success(), "{:?}", presented.status);
    let r = SpeedAccuracy::measure_at(true, Some(&presented)).expect("quick report measures");

    // (a) DOPRI5: error of x(T) falls with rtol (within a factor 3 of noise per rung) and by
    // orders of magnitude over the ladder; the event times converge too.
    let dopri: Vec<_> = r.sim.iter().filter(|x| x.method == "dopri5").collect();
    assert!(dopri.len() >= 3);
    assert!(dopri.iter().all(|x| x.failure.is_none()), "{dopri:?}");
    for w in dopri.windows(2) {
        assert!(w[0].parameter > w[1].parameter);
        assert!(w[1].error < 3.0 * w[0].error, "{:?} then {:?}", w[0], w[1]);
    }
    let (first, last) = (dopri[0], dopri[dopri.len() - 1]);
    assert!(last.error < 1e-3 * first.error, "{first:?} .. {last:?}");
    assert!(last.same_events && last.event_time_error < 1e-6, "{last:?}");
    // The work grows as the tolerance tightens.
    assert!(last.rhs_evals > first.rhs_evals);
    // RK4: a 10x smaller step does not increase the error.
    let rk4: Vec<_> = r.sim.iter().filter(|x| x.method == "rk4").collect();
    assert!(rk4.len() >= 2);
    assert!(rk4[1].error <= rk4[0].error * 1.5, "{rk4:?}");

    // (b) the reference is converged: hp refinement reached its tolerance, and its stated
    // error of J is the change over the last refinement rounds.
    let (desc, j_ref, _) = &r.mesh_reference;
    assert!(
        desc.contains("refined") && desc.contains("(converged;"),
        "{desc}"
    );
    assert!(
        desc.contains("relative change of J in the last rounds"),
        "{desc}"
    );
    assert!(j_ref.is_finite() && *j_ref > 0.0);
    // (b) mesh rows on the reference's optimum agree with it to a few percent; the ε ladder:
    // |sat − sat_smooth| ≤ ε, and p_c moves by sat(α)·ê_x3 with |ê_x3| = 1, so the
    // contact-point error is at most ε, and it falls as ε does.
    assert!(!r.mesh.is_empty());
    for m in r.mesh.iter().filter(|m| m.same_branch) {
        assert!(m.rel_error < 0.1, "{m:?}");
    }
    // A row re-solved from the reference is held to the same accuracy except on the coarsest
    // quick mesh (2 elements × 5 points: ≈ 11 % off, a discretisation error, not a branch).
    for m in r.mesh.iter().filter(|m| m.warm_rel_error.is_finite()) {
        let tol = if m.points <= 10 { 0.2 } else { 0.1 };
        assert!(m.warm_rel_error < tol, "{m:?}");
    }
    assert!(
        r.mesh
            .iter()
            .any(|m| m.same_branch || m.warm_rel_error.is_finite()),
        "no mesh on the reference optimum: {:?}",
        r.mesh
    );
    // (b) at the presented optimum: its refined reference is the presented solution's J to
    // the discretisation error of its 3 × 10 mesh (refinement moves J, it does not change the
    // optimum), the Radau meshes warm-started from it stay on it, their error falls as the
    // elements double, and the finest one's J is the presented J to the error of the coarser
    // of the two meshes.
    let p = r.mesh_presented.as_ref().expect("a presented reference");
    assert!(p.description.contains("(converged;"), "{}", p.description);
    assert_eq!(p.presented_objective, presented.objective);
    let j_ref_p = p.objective;
    assert!(
        (presented.objective - j_ref_p).abs() <= 1e-2 * j_ref_p,
        "presented J {} vs its reference {j_ref_p}",
        presented.objective
    );
    let radau: Vec<_> = r.mesh.iter().filter(|m| m.scheme == "Radau").collect();
    assert!(radau.len() >= 2);
    assert!(
        radau.iter().all(|m| m.presented_rel_error.is_finite()),
        "{radau:?}"
    );
    let (coarse, fine) = (radau[0], radau[radau.len() - 1]);
    assert!(
        fine.presented_rel_error < coarse.presented_rel_error,
        "{coarse:?} then {fine:?}"
    );
    assert!(
        (fine.presented_objective - presented.objective).abs()
            <= coarse.presented_rel_error * j_ref_p,
        "{fine:?} vs presented J {}",
        presented.objective
    );
    let eps: Vec<_> = r.eps.iter().filter(|e| e.solved).collect();
    assert!(eps.len() >= 2, "{:?}", r.eps);
    for e in &eps {
        assert!(e.contact_point_error <= e.eps, "{e:?}");
    }
    for w in eps.windows(2) {
        assert!(
            w[1].contact_point_error < w[0].contact_point_error,
            "{:?} then {:?}",
            w[0],
            w[1]
        );
    }

    // (c) every kernel in every variant, errors against double-double.
    assert_eq!(r.kernels.len(), VARIANT_KERNELS.len() * VARIANTS.len());
    for k in VARIANT_KERNELS {
        let row = |v: &str| {
            r.kernels
                .iter()
                .find(|x| x.kernel == k && x.variant == v)
                .unwrap_or_else(|| panic!("{k} {v} missing"))
        };
        let plain = row("f64 baked");
        let fma = row("f64 FMA");
        let rt = row("f64 runtime params");
        let single = row("f32 baked");
        for x in [plain, fma, rt] {
            assert!(x.max_rel_error <= 1e-13, "{x:?}");
        }
        assert!(
            single.max_rel_error >= 1e-8 && single.max_rel_error < 1e-4,
            "{single:?}"
        );
        assert!(
            fma.max_rel_error <= 2.0 * plain.max_rel_error + f64::EPSILON,
            "{fma:?} vs {plain:?}"
        );
        for x in [plain, fma, rt, single] {
            assert!(x.ns_per_call.is_finite() && x.ns_per_call > 0.0, "{x:?}");
            assert!(x.median_rel_error <= x.max_rel_error);
        }
    }

    // Figures: every image the Markdown links exists and is non-empty.
    let dir = cli_util::tmpdir("report");
    let _ = std::fs::remove_dir_all(&dir);
    let md = r.write(&dir).expect("report renders");
    let links: Vec<&str> = md
        .split("](")
        .skip(1)
        .filter_map(|s| s.split(')').next())
        .collect();
    assert!(links.len() >= 5, "{md}");
    for l in links {
        assert!(l.starts_with("figures/") && l.ends_with(".svg"), "{l}");
        let len = std::fs::metadata(dir.join(l)).map(|m| m.len()).unwrap_or(0);
        assert!(len > 1000, "{l}: {len} bytes");
        let png = dir.join(l.replace(".svg", ".png"));
        assert!(std::fs::metadata(&png).map(|m| m.len()).unwrap_or(0) > 1000);
    }
    // Tables: one row per measurement.
    assert_eq!(
        md.lines()
            .filter(|l| l.starts_with("| dopri5") || l.starts_with("| rk4"))
            .count(),
        r.sim.len()
    );
    let _ = std::fs::remove_dir_all(&dir);
}
