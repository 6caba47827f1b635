//! Hock–Schittkowski problems HS001 to HS039.

use super::{D, Hs, INF, none, rosen};

/// Hock–Schittkowski problems HS001 to HS039, in the book's order.
pub(super) fn list() -> Vec<Hs> {
    let s2 = 2f64.sqrt();
    let s3 = 3f64.sqrt();
    let pi = std::f64::consts::PI;
    vec![
        hs!(
            "HS001",
            "bounds, rosenbrock",
            x0 = [-2.0, 1.0],
            xl = [-INF, -1.5],
            xu = [INF, INF],
            neq = 0,
            m = 0,
            f = rosen,
            g = none,
            fstar = 0.0,
            xstar = Some(vec![1.0, 1.0])
        ),
        hs!(
            "HS002",
            "active bound",
            x0 = [-2.0, 1.0],
            xl = [-INF, 1.5],
            xu = [INF, INF],
            neq = 0,
            m = 0,
            f = rosen,
            g = none,
            fstar = 0.0504261879,
            xstar = Some(vec![1.224370749, 1.5])
        ),
        hs!(
            "HS003",
            "active bound, ill-conditioned",
            x0 = [10.0, 1.0],
            xl = [-INF, 0.0],
            xu = [INF, INF],
            neq = 0,
            m = 0,
            f = |x| x[1] + 1e-5 * (x[1] - x[0]).powi(2),
            g = none,
            fstar = 0.0,
            xstar = Some(vec![0.0, 0.0])
        ),
        hs!(
            "HS004",
            "active bounds",
            x0 = [1.125, 0.125],
            xl = [1.0, 0.0],
            xu = [INF, INF],
            neq = 0,
            m = 0,
            f = |x| (x[0] + 1.0).powi(3) / 3.0 + x[1],
            g = none,
            fstar = 8.0 / 3.0,
            xstar = Some(vec![1.0, 0.0])
        ),
        hs!(
            "HS005",
            "non-convex, bounds",
            x0 = [0.0, 0.0],
            xl = [-1.5, -3.0],
            xu = [4.0, 3.0],
            neq = 0,
            m = 0,
            f = |x| (x[0] + x[1]).sin() + (x[0] - x[1]).powi(2) - 1.5 * x[0] + 2.5 * x[1] + 1.0,
            g = none,
            fstar = -0.5 * s3 - pi / 3.0,
            xstar = Some(vec![0.5 - pi / 3.0, -0.5 - pi / 3.0])
        ),
        hs!(
            "HS006",
            "equality",
            x0 = [-1.2, 1.0],
            xl = [-INF; 2],
            xu = [INF; 2],
            neq = 1,
            m = 1,
            f = |x| (1.0 - x[0]).powi(2),
            g = |x| vec![10.0 * (x[1] - x[0] * x[0])],
            fstar = 0.0,
            xstar = Some(vec![1.0, 1.0])
        ),
        hs!(
            "HS007",
            "equality, non-convex",
            x0 = [2.0, 2.0],
            xl = [-INF; 2],
            xu = [INF; 2],
            neq = 1,
            m = 1,
            f = |x| (1.0 + x[0] * x[0]).ln() - x[1],
            g = |x| vec![(1.0 + x[0] * x[0]).powi(2) + x[1] * x[1] - 4.0],
            fstar = -s3,
            xstar = Some(vec![0.0, s3])
        ),
        hs!(
            "HS008",
            "constant objective, feasibility",
            x0 = [2.0, 1.0],
            xl = [-INF; 2],
            xu = [INF; 2],
            neq = 2,
            m = 2,
            f = |_x| D::cst(-1.0),
            g = |x| vec![x[0] * x[0] + x[1] * x[1] - 25.0, x[0] * x[1] - 9.0],
            fstar = -1.0,
            xstar = None
        ),
        hs!(
            "HS009",
            "non-convex, periodic",
            x0 = [0.0, 0.0],
            xl = [-INF; 2],
            xu = [INF; 2],
            neq = 1,
            m = 1,
            f = |x| (std::f64::consts::PI * x[0] / 12.0).sin()
                * (std::f64::consts::PI * x[1] / 16.0).cos(),
            g = |x| vec![4.0 * x[0] - 3.0 * x[1]],
            fstar = -0.5,
            xstar = Some(vec![-3.0, -4.0])
        ),
        hs!(
            "HS010",
            "inequality, linear objective",
            x0 = [-10.0, 10.0],
            xl = [-INF; 2],
            xu = [INF; 2],
            neq = 0,
            m = 1,
            f = |x| x[0] - x[1],
            g = |x| vec![-3.0 * x[0] * x[0] + 2.0 * x[0] * x[1] - x[1] * x[1] + 1.0],
            fstar = -1.0,
            xstar = Some(vec![0.0, 1.0])
        ),
        hs!(
            "HS011",
            "inequality",
            x0 = [4.9, 0.1],
            xl = [-INF; 2],
            xu = [INF; 2],
            neq = 0,
            m = 1,
            f = |x| (x[0] - 5.0).powi(2) + x[1] * x[1] - 25.0,
            g = |x| vec![-x[0] * x[0] + x[1]],
            fstar = -8.498464223,
            xstar = Some(vec![1.234772892632396, 1.524664093087327])
        ),
        hs!(
            "HS012",
            "inequality",
            x0 = [0.0, 0.0],
            xl = [-INF; 2],
            xu = [INF; 2],
            neq = 0,
            m = 1,
            f = |x| 0.5 * x[0] * x[0] + x[1] * x[1] - x[0] * x[1] - 7.0 * x[0] - 7.0 * x[1],
            g = |x| vec![25.0 - 4.0 * x[0] * x[0] - x[1] * x[1]],
            fstar = -30.0,
            xstar = Some(vec![2.0, 3.0])
        ),
        hs!(
            "HS013",
            "degenerate (no constraint qualification)",
            x0 = [-2.0, -2.0],
            xl = [0.0, 0.0],
            xu = [INF, INF],
            neq = 0,
            m = 1,
            f = |x| (x[0] - 2.0).powi(2) + x[1] * x[1],
            g = |x| vec![(1.0 - x[0]).powi(3) - x[1]],
            fstar = 1.0,
            xstar = Some(vec![1.0, 0.0])
        ),
        hs!(
            "HS014",
            "mixed",
            x0 = [2.0, 2.0],
            xl = [-INF; 2],
            xu = [INF; 2],
            neq = 1,
            m = 2,
            f = |x| (x[0] - 2.0).powi(2) + (x[1] - 1.0).powi(2),
            g = |x| vec![
                x[0] - 2.0 * x[1] + 1.0,
                -0.25 * x[0] * x[0] - x[1] * x[1] + 1.0
            ],
            fstar = 9.0 - 2.875 * 7f64.sqrt(),
            xstar = Some(vec![0.5 * (7f64.sqrt() - 1.0), 0.25 * (7f64.sqrt() + 1.0)])
        ),
        hs!(
            "HS015",
            "non-convex, active bound",
            x0 = [-2.0, 1.0],
            xl = [-INF, -INF],
            xu = [0.5, INF],
            neq = 0,
            m = 2,
            f = rosen,
            g = |x| vec![x[0] * x[1] - 1.0, x[0] + x[1] * x[1]],
            fstar = 306.5,
            xstar = Some(vec![0.5, 2.0])
        ),
        hs!(
            "HS016",
            "non-convex, bounds",
            x0 = [-2.0, 1.0],
            xl = [-0.5, -INF],
            xu = [0.5, 1.0],
            neq = 0,
            m = 2,
            f = rosen,
            g = |x| vec![x[0] + x[1] * x[1], x[0] * x[0] + x[1]],
            fstar = 0.25,
            xstar = Some(vec![0.5, 0.25])
        ),
        hs!(
            "HS017",
            "non-convex, degenerate",
            x0 = [-2.0, 1.0],
            xl = [-0.5, -INF],
            xu = [0.5, 1.0],
            neq = 0,
            m = 2,
            f = rosen,
            g = |x| vec![x[1] * x[1] - x[0], x[0] * x[0] - x[1]],
            fstar = 1.0,
            xstar = Some(vec![0.0, 0.0])
        ),
        hs!(
            "HS018",
            "non-convex",
            x0 = [2.0, 2.0],
            xl = [2.0, 0.0],
            xu = [50.0, 50.0],
            neq = 0,
            m = 2,
            f = |x| 0.01 * x[0] * x[0] + x[1] * x[1],
            g = |x| vec![x[0] * x[1] - 25.0, x[0] * x[0] + x[1] * x[1] - 25.0],
            fstar = 5.0,
            xstar = Some(vec![250f64.sqrt(), 2.5f64.sqrt()])
        ),
        hs!(
            "HS019",
            "non-convex",
            x0 = [20.1, 5.84],
            xl = [13.0, 0.0],
            xu = [100.0, 100.0],
            neq = 0,
            m = 2,
            f = |x| (x[0] - 10.0).powi(3) + (x[1] - 20.0).powi(3),
            g = |x| vec![
                (x[0] - 5.0).powi(2) + (x[1] - 5.0).powi(2) - 100.0,
                -(x[1] - 5.0).powi(2) - (x[0] - 6.0).powi(2) + 82.81
            ],
            fstar = -6961.81381,
            xstar = Some(vec![14.095, 0.84296079])
        ),
        hs!(
            "HS020",
            "non-convex",
            x0 = [-2.0, 1.0],
            xl = [-0.5, -INF],
            xu = [0.5, INF],
            neq = 0,
            m = 3,
            f = rosen,
            g = |x| vec![
                x[0] + x[1] * x[1],
                x[0] * x[0] + x[1],
                x[0] * x[0] + x[1] * x[1] - 1.0
            ],
            fstar = 81.5 - 25.0 * s3,
            xstar = Some(vec![0.5, 0.5 * s3])
        ),
        hs!(
            "HS021",
            "infeasible start, active bound",
            x0 = [-1.0, -1.0],
            xl = [2.0, -50.0],
            xu = [50.0, 50.0],
            neq = 0,
            m = 1,
            f = |x| 0.01 * x[0] * x[0] + x[1] * x[1] - 100.0,
            g = |x| vec![10.0 * x[0] - x[1] - 10.0],
            fstar = -99.96,
            xstar = Some(vec![2.0, 0.0])
        ),
        hs!(
            "HS022",
            "inequality",
            x0 = [2.0, 2.0],
            xl = [-INF; 2],
            xu = [INF; 2],
            neq = 0,
            m = 2,
            f = |x| (x[0] - 2.0).powi(2) + (x[1] - 1.0).powi(2),
            g = |x| vec![-x[0] - x[1] + 2.0, -x[0] * x[0] + x[1]],
            fstar = 1.0,
            xstar = Some(vec![1.0, 1.0])
        ),
        hs!(
            "HS023",
            "non-convex",
            x0 = [3.0, 1.0],
            xl = [-50.0; 2],
            xu = [50.0; 2],
            neq = 0,
            m = 5,
            f = |x| x[0] * x[0] + x[1] * x[1],
            g = |x| vec![
                x[0] + x[1] - 1.0,
                x[0] * x[0] + x[1] * x[1] - 1.0,
                9.0 * x[0] * x[0] + x[1] * x[1] - 9.0,
                x[0] * x[0] - x[1],
                x[1] * x[1] - x[0],
            ],
            fstar = 2.0,
            xstar = Some(vec![1.0, 1.0])
        ),
        hs!(
            "HS024",
            "non-convex, linear constraints",
            x0 = [1.0, 0.5],
            xl = [0.0, 0.0],
            xu = [INF, INF],
            neq = 0,
            m = 3,
            f = |x| ((x[0] - 3.0).powi(2) - 9.0) * x[1].powi(3) / (27.0 * 3f64.sqrt()),
            g = |x| {
                let r = 3f64.sqrt();
                vec![x[0] / r - x[1], x[0] + r * x[1], -x[0] - r * x[1] + 6.0]
            },
            fstar = -1.0,
            xstar = Some(vec![3.0, s3])
        ),
        hs!(
            "HS026",
            "equality, singular Hessian at x*",
            x0 = [-2.6, 2.0, 2.0],
            xl = [-INF; 3],
            xu = [INF; 3],
            neq = 1,
            m = 1,
            f = |x| (x[0] - x[1]).powi(2) + (x[1] - x[2]).powi(4),
            g = |x| vec![(1.0 + x[1] * x[1]) * x[0] + x[2].powi(4) - 3.0],
            fstar = 0.0,
            xstar = Some(vec![1.0, 1.0, 1.0])
        ),
        hs!(
            "HS027",
            "equality",
            x0 = [2.0, 2.0, 2.0],
            xl = [-INF; 3],
            xu = [INF; 3],
            neq = 1,
            m = 1,
            f = |x| 0.01 * (x[0] - 1.0).powi(2) + (x[1] - x[0] * x[0]).powi(2),
            g = |x| vec![x[0] + x[2] * x[2] + 1.0],
            fstar = 0.04,
            xstar = Some(vec![-1.0, 1.0, 0.0])
        ),
        hs!(
            "HS028",
            "equality QP",
            x0 = [-4.0, 1.0, 1.0],
            xl = [-INF; 3],
            xu = [INF; 3],
            neq = 1,
            m = 1,
            f = |x| (x[0] + x[1]).powi(2) + (x[1] + x[2]).powi(2),
            g = |x| vec![x[0] + 2.0 * x[1] + 3.0 * x[2] - 1.0],
            fstar = 0.0,
            xstar = Some(vec![0.5, -0.5, 0.5])
        ),
        hs!(
            "HS029",
            "non-convex",
            x0 = [1.0, 1.0, 1.0],
            xl = [-INF; 3],
            xu = [INF; 3],
            neq = 0,
            m = 1,
            f = |x| -x[0] * x[1] * x[2],
            g = |x| vec![-x[0] * x[0] - 2.0 * x[1] * x[1] - 4.0 * x[2] * x[2] + 48.0],
            fstar = -16.0 * s2,
            xstar = Some(vec![4.0, 2.0 * s2, 2.0])
        ),
        hs!(
            "HS030",
            "active bound",
            x0 = [1.0, 1.0, 1.0],
            xl = [1.0, -10.0, -10.0],
            xu = [10.0; 3],
            neq = 0,
            m = 1,
            f = |x| x[0] * x[0] + x[1] * x[1] + x[2] * x[2],
            g = |x| vec![x[0] * x[0] + x[1] * x[1] - 1.0],
            fstar = 1.0,
            xstar = Some(vec![1.0, 0.0, 0.0])
        ),
        hs!(
            "HS031",
            "non-convex constraint",
            x0 = [1.0, 1.0, 1.0],
            xl = [-10.0, 1.0, -10.0],
            xu = [10.0, 10.0, 1.0],
            neq = 0,
            m = 1,
            f = |x| 9.0 * x[0] * x[0] + x[1] * x[1] + 9.0 * x[2] * x[2],
            g = |x| vec![x[0] * x[1] - 1.0],
            fstar = 6.0,
            xstar = Some(vec![1.0 / s3, s3, 0.0])
        ),
        hs!(
            "HS032",
            "active bounds",
            x0 = [0.1, 0.7, 0.2],
            xl = [0.0; 3],
            xu = [INF; 3],
            neq = 1,
            m = 2,
            f = |x| (x[0] + 3.0 * x[1] + x[2]).powi(2) + 4.0 * (x[0] - x[1]).powi(2),
            g = |x| vec![
                1.0 - x[0] - x[1] - x[2],
                6.0 * x[1] + 4.0 * x[2] - x[0].powi(3) - 3.0
            ],
            fstar = 1.0,
            xstar = Some(vec![0.0, 0.0, 1.0])
        ),
        hs!(
            "HS033",
            "non-convex, active bound",
            x0 = [0.0, 0.0, 3.0],
            xl = [0.0; 3],
            xu = [INF, INF, 5.0],
            neq = 0,
            m = 2,
            f = |x| (x[0] - 1.0) * (x[0] - 2.0) * (x[0] - 3.0) + x[2],
            g = |x| vec![
                x[2] * x[2] - x[1] * x[1] - x[0] * x[0],
                x[0] * x[0] + x[1] * x[1] + x[2] * x[2] - 4.0
            ],
            fstar = s2 - 6.0,
            xstar = Some(vec![0.0, s2, s2])
        ),
        hs!(
            "HS034",
            "exponential constraints",
            x0 = [0.0, 1.05, 2.9],
            xl = [0.0; 3],
            xu = [100.0, 100.0, 10.0],
            neq = 0,
            m = 2,
            f = |x| -x[0],
            g = |x| vec![x[1] - x[0].exp(), x[2] - x[1].exp()],
            fstar = -libm::log(libm::log(10f64)),
            xstar = Some(vec![libm::log(libm::log(10f64)), libm::log(10f64), 10.0])
        ),
        hs!(
            "HS035",
            "convex QP",
            x0 = [0.5, 0.5, 0.5],
            xl = [0.0; 3],
            xu = [INF; 3],
            neq = 0,
            m = 1,
            f = |x| 9.0 - 8.0 * x[0] - 6.0 * x[1] - 4.0 * x[2]
                + 2.0 * x[0] * x[0]
                + 2.0 * x[1] * x[1]
                + x[2] * x[2]
                + 2.0 * x[0] * x[1]
                + 2.0 * x[0] * x[2],
            g = |x| vec![3.0 - x[0] - x[1] - 2.0 * x[2]],
            fstar = 1.0 / 9.0,
            xstar = Some(vec![4.0 / 3.0, 7.0 / 9.0, 4.0 / 9.0])
        ),
        hs!(
            "HS036",
            "active bounds",
            x0 = [10.0, 10.0, 10.0],
            xl = [0.0; 3],
            xu = [20.0, 11.0, 42.0],
            neq = 0,
            m = 1,
            f = |x| -x[0] * x[1] * x[2],
            g = |x| vec![72.0 - x[0] - 2.0 * x[1] - 2.0 * x[2]],
            fstar = -3300.0,
            xstar = Some(vec![20.0, 11.0, 15.0])
        ),
        hs!(
            "HS037",
            "non-convex",
            x0 = [10.0, 10.0, 10.0],
            xl = [0.0; 3],
            xu = [42.0; 3],
            neq = 0,
            m = 2,
            f = |x| -x[0] * x[1] * x[2],
            g = |x| vec![
                72.0 - x[0] - 2.0 * x[1] - 2.0 * x[2],
                x[0] + 2.0 * x[1] + 2.0 * x[2]
            ],
            fstar = -3456.0,
            xstar = Some(vec![24.0, 12.0, 12.0])
        ),
        hs!(
            "HS038",
            "Wood function, bounds",
            x0 = [-3.0, -1.0, -3.0, -1.0],
            xl = [-10.0; 4],
            xu = [10.0; 4],
            neq = 0,
            m = 0,
            f = |x| 100.0 * (x[1] - x[0] * x[0]).powi(2)
                + (1.0 - x[0]).powi(2)
                + 90.0 * (x[3] - x[2] * x[2]).powi(2)
                + (1.0 - x[2]).powi(2)
                + 10.1 * ((x[1] - 1.0).powi(2) + (x[3] - 1.0).powi(2))
                + 19.8 * (x[1] - 1.0) * (x[3] - 1.0),
            g = none,
            fstar = 0.0,
            xstar = Some(vec![1.0; 4])
        ),
        hs!(
            "HS039",
            "equality, linear objective",
            x0 = [2.0; 4],
            xl = [-INF; 4],
            xu = [INF; 4],
            neq = 2,
            m = 2,
            f = |x| -x[0],
            g = |x| vec![
                x[1] - x[0].powi(3) - x[2] * x[2],
                x[0] * x[0] - x[1] - x[3] * x[3]
            ],
            fstar = -1.0,
            xstar = Some(vec![1.0, 1.0, 0.0, 0.0])
        ),
    ]
}
