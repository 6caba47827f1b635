//! Tests of the multifrontal LDLᵀ with threshold pivoting and delayed pivots
//! (`kkt::multifrontal`): reconstruction, bounded `L`, inertia
//! against dense eigenvalues, delayed constraint rows and singular matrices.

use super::*;

/// Random KKT `[H + Σ, Jᵀ; J, −δ_c I]` for the pivoting tests: an indefinite block-banded `H`
/// (dense element blocks, some zero diagonals), each constraint row coupling five variables and
/// a dense last column, `Σ = sigma_big` on every `big_every`-th variable (a large barrier
/// term; 0 disables) and `shift` on the others. Returns the pattern (values assembled) and the
/// dense matrix.
fn pivoting_kkt(
    seed: u64,
    n: usize,
    m: usize,
    shift: f64,
    sigma_big: f64,
    big_every: usize,
    delta_c: f64,
) -> (KktPattern, Vec<Vec<f64>>) {
    let shape = KktShape {
        zero_diag_every: 5,
        block: 6,
        density: 0.6,
        row_vars: 5,
        stride: 2,
    };
    let diag_x: Vec<f64> = (0..n)
        .map(|i| {
            if big_every > 0 && i % big_every == 1 {
                sigma_big
            } else {
                shift
            }
        })
        .collect();
    banded_kkt(seed, (n, m), &shape, &diag_x, delta_c)
}

/// Inertia of a dense symmetric matrix from Jacobi eigenvalues of its diagonally equilibrated
/// congruent `S A S`, `S = diag(1/√max(|a_ii|, 1))` (same inertia by Sylvester's law; the
/// scaling keeps barrier terms of 1e10 from swamping the small eigenvalues in rounding), and
/// the smallest eigenvalue magnitude of `S A S` (how clearly the reference decides).
fn dense_inertia(a: &[Vec<f64>]) -> (Inertia, f64) {
    let n = a.len();
    let s: Vec<f64> = (0..n)
        .map(|i| 1.0 / a[i][i].abs().max(1.0).sqrt())
        .collect();
    let mut b: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..n).map(|j| s[i] * a[i][j] * s[j]).collect())
        .collect();
    let eig = dense_eigs(&mut b);
    let inertia = eig_inertia(&eig);
    (
        inertia,
        eig.iter().fold(f64::INFINITY, |m, e| m.min(e.abs())),
    )
}

/// Checks one multifrontal factorization against independent computations: `Q K Qᵀ = L D Lᵀ`
/// entrywise relative to `|L| |D| |Lᵀ|` (≤ 1e-12), `L` unit lower triangular with entries
/// bounded by the pivot test, `D` block diagonal with 1 × 1 / 2 × 2 blocks, the inertia against
/// dense eigenvalues, and the unrefined solution against the residual. Returns the pivot
/// statistics.
fn check_multifrontal(
    pat: &KktPattern,
    dense: &[Vec<f64>],
    label: &str,
    amalgamation: usize,
) -> (usize, usize, usize) {
    let dim = pat.mat.dim;
    let mut s = SparseLdlt::with_options(LdltOptions {
        backend: LdltBackend::Multifrontal,
        amalgamation,
        pivot_threshold: 0.01,
        ..LdltOptions::default()
    });
    s.analyse(dim, &pat.mat.col_ptr, &pat.mat.row_idx).unwrap();
    let inertia = s.factor(&pat.mat.values).expect("factor");
    let stats = s.pivot_statistics();
    let Kernel::Multifrontal(mf) = &s.kernel else {
        panic!("{label}: multifrontal kernel");
    };
    let (q, l, d) = mf.dense_factor();
    let mut sorted = q.clone();
    sorted.sort_unstable();
    assert_eq!(sorted, (0..dim).collect::<Vec<_>>(), "{label}: order");
    let mut lmax = 0.0f64;
    for i in 0..dim {
        assert_eq!(l[i][i], 1.0, "{label}");
        for j in i + 1..dim {
            assert_eq!(l[i][j], 0.0, "{label}: L upper");
        }
        for j in 0..i {
            lmax = lmax.max(l[i][j].abs());
            if i > j + 1 {
                assert_eq!(d[i][j], 0.0, "{label}: D not block diagonal");
            }
        }
    }
    // The threshold test bounds |L| by 1/u (u = 0.01) in the non-root fronts; the root's
    // Bunch–Kaufman pivots stay far below that on these matrices.
    assert!(
        lmax <= 1.0 / s.options().pivot_threshold,
        "{label}: max |L| {lmax}"
    );
    let mut ld = vec![vec![0.0; dim]; dim];
    let mut ld_abs = vec![vec![0.0; dim]; dim];
    for i in 0..dim {
        for k in 0..=i {
            if l[i][k] != 0.0 {
                for j in k.saturating_sub(1)..(k + 2).min(dim) {
                    ld[i][j] += l[i][k] * d[k][j];
                    ld_abs[i][j] += (l[i][k] * d[k][j]).abs();
                }
            }
        }
    }
    let mut max_ratio = 0.0f64;
    for i in 0..dim {
        for j in 0..=i {
            let (mut ldl, mut bound) = (0.0, 0.0);
            for k in 0..=j {
                ldl += ld[i][k] * l[j][k];
                bound += ld_abs[i][k] * l[j][k].abs();
            }
            let err = (ldl - dense[q[i]][q[j]]).abs();
            if err > 0.0 {
                max_ratio = max_ratio.max(err / bound.max(f64::MIN_POSITIVE));
            }
        }
    }
    assert!(max_ratio <= 1e-12, "{label}: backward error {max_ratio}");
    let (expect, min_eig) = dense_inertia(dense);
    assert!(min_eig > 1e-9, "{label}: reference undecided ({min_eig})");
    assert_eq!(inertia, expect, "{label}");
    // Bounded growth: the direct solve is accurate without refinement.
    let b: Vec<f64> = (0..dim).map(|i| libm::sin(i as f64 * 0.37) + 0.1).collect();
    let mut x = b.clone();
    s.solve(&mut x).unwrap();
    let mut r = vec![0.0; dim];
    pat.mat.sym_matvec(&x, &mut r);
    let kmax = pat.mat.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let xmax = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let res = r
        .iter()
        .zip(&b)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        res <= 1e-12 * (kmax * xmax + 1.0),
        "{label}: unrefined residual {res} (|K| {kmax}, |x| {xmax})"
    );
    stats
}

/// The multifrontal LDLᵀ with threshold pivoting on quasidefinite and indefinite KKTs, with
/// δ_c from 1e-2 down to 1e-9 and 0 and barrier terms Σ = 1e10 on variables coupled to
/// constraint rows (where a static 2 × 2 (variable, row) pivot has `det ≈ −Σ δ_c` and an
/// inverse of order 1/δ_c): exact reconstruction, bounded `L`, inertia of the matrix, accurate
/// unrefined solves; constraint rows that AMD eliminates before their variables are delayed to
/// a parent front.
#[test]
fn multifrontal_threshold_pivoting_reconstructs_with_the_right_inertia() {
    let mut delayed_total = 0;
    let mut two_total = 0;
    for (seed, n, m, shift, sigma, every, dc) in [
        (1, 40, 24, 0.0, 0.0, 0, 1e-9),
        (2, 40, 24, 1.0, 0.0, 0, 0.0),
        (3, 90, 50, -0.3, 1e10, 4, 1e-9),
        (4, 90, 50, 5.0, 1e10, 3, 1e-9),
        (5, 120, 70, 0.0, 1e10, 4, 0.0),
        (6, 60, 55, 0.5, 1e10, 2, 1e-9),
        (7, 80, 40, 2.0, 0.0, 0, 1e-2),
        (8, 80, 60, 0.0, 1e10, 5, 1e-9),
    ] {
        let (pat, dense) = pivoting_kkt(seed, n, m, shift, sigma, every, dc);
        let label = format!("seed {seed} (Σ {sigma:e} every {every}, δ_c {dc:e})");
        // Fundamental supernodes (small fronts: many delays) and amalgamated ones.
        for nemin in [1, 16] {
            let label = format!("{label}, nemin {nemin}");
            let (delayed, two, stat) = check_multifrontal(&pat, &dense, &label, nemin);
            assert_eq!(stat, 0, "{label}: static pivots on a nonsingular KKT");
            delayed_total += delayed;
            two_total += two;
        }
    }
    assert!(delayed_total > 0, "no delayed pivot exercised");
    assert!(two_total > 0, "no 2 × 2 pivot exercised");
}

/// A constraint row that AMD eliminates first (a leaf of the elimination tree, alone in its
/// front) with the pivot −δ_c fails the threshold test and is delayed to its parent, where it
/// forms a 2 × 2 pivot with a variable or follows them; plain AMD's unpivoted factor of the
/// same matrix with a huge Σ on that variable reports the wrong inertia or grows.
#[test]
fn multifrontal_delays_a_bare_constraint_row() {
    // x0 has Σ = 1e10 and a single constraint row c0 = x0 + x1 − x2 (so AMD's minimum degree
    // takes c0 or x0 early); H = diag(big, 1, −0.5) + couplings.
    let hess = [(0, 0), (1, 1), (2, 2), (2, 1)];
    let jac = [(0, 0), (0, 1), (0, 2)];
    for dc in [1e-9, 0.0] {
        let mut pat = KktPattern::new(3, 1, &hess, &jac);
        pat.assemble(
            &[0.0, 1.0, -0.5, 0.2],
            &[1.0, 1.0, -1.0],
            &[1e10, 0.0, 0.0],
            -dc,
        );
        let mut dense = vec![vec![0.0; 4]; 4];
        for j in 0..4 {
            for p in pat.mat.col_ptr[j]..pat.mat.col_ptr[j + 1] {
                let i = pat.mat.row_idx[p];
                dense[i][j] += pat.mat.values[p];
                if i != j {
                    dense[j][i] += pat.mat.values[p];
                }
            }
        }
        check_multifrontal(&pat, &dense, &format!("δ_c {dc:e}"), 1);
    }
    // Random collocation-like KKTs with δ_c = 0: every constraint row that AMD eliminates
    // before its variables is delayed (a pivot 0 never passes the test).
    let (pat, dense) = pivoting_kkt(11, 60, 40, 1.0, 0.0, 0, 0.0);
    let (delayed, ..) = check_multifrontal(&pat, &dense, "δ_c 0", 1);
    assert!(delayed > 0, "no delay with zero constraint pivots");
}

/// Singular KKTs: with static pivoting off, a structurally singular matrix (a variable in
/// neither H nor J) is reported as such; with it on, the zero pivot is replaced in the root
/// front, counted, and the factor has the inertia of the regularized matrix.
#[test]
fn multifrontal_reports_singular() {
    let (pat, s) = singular_without_static_pivoting(LdltBackend::Multifrontal);
    assert!(matches!(s.kernel, Kernel::Multifrontal(_)));
    let mut s = SparseLdlt::with_backend(LdltBackend::Multifrontal);
    s.analyse(4, &pat.mat.col_ptr, &pat.mat.row_idx).unwrap();
    let inertia = s.factor(&pat.mat.values).expect("static pivoting");
    assert_eq!(s.pivot_statistics().2, 1, "one static pivot");
    // K + δ e₁e₁ᵀ (δ = +pivot_delta on x1's zero column): [1 0 .5 1; 0 δ 0 0; .5 0 0 2; 1 0 2 0]
    // has eigenvalues δ and those of the 3 × 3 block, of determinant −2 and trace 1: (3, 1).
    assert_eq!(
        inertia,
        Inertia {
            positive: 3,
            negative: 1,
            zero: 0
        }
    );
}
