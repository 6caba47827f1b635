//! Tests of the KKT backends against independent references: dense Jacobi eigenvalues for the
//! inertia, `P K Pᵀ = L D Lᵀ` reconstruction, refined residuals, and faer's own factorization
//! for the bitwise-identical simplicial path.

use super::*;

mod multifrontal;
mod speculative;

/// max |K x − b| after solving K x = b with `s` and `steps` refinement steps, for a fixed
/// right-hand side.
fn refined_residual(s: &mut SparseLdlt, pat: &KktPattern, steps: usize) -> f64 {
    let dim = pat.mat.dim;
    let b: Vec<f64> = (0..dim).map(|i| libm::sin(i as f64 * 0.37) + 0.1).collect();
    let mut x = b.clone();
    s.solve(&mut x).unwrap();
    let mut r = vec![0.0; dim];
    for _ in 0..steps {
        pat.mat.sym_matvec(&x, &mut r);
        let mut c: Vec<f64> = b.iter().zip(&r).map(|(b, r)| b - r).collect();
        s.solve(&mut c).unwrap();
        x.iter_mut().zip(&c).for_each(|(x, c)| *x += c);
    }
    pat.mat.sym_matvec(&x, &mut r);
    r.iter()
        .zip(&b)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
}

/// Dense inertia by Gaussian elimination with symmetric (diagonal) Bunch–Parlett-free
/// eigen-free counting: Sylvester on a dense LDLᵀ with full symmetric pivoting by largest
/// diagonal is not always possible, so use the Jacobi eigenvalue method (independent of faer).
/// Inertia from eigenvalues (a zero eigenvalue counts in neither class: the test matrices are
/// nonsingular).
fn eig_inertia(eig: &[f64]) -> Inertia {
    Inertia {
        positive: eig.iter().filter(|&&e| e > 0.0).count(),
        negative: eig.iter().filter(|&&e| e < 0.0).count(),
        zero: 0,
    }
}

fn dense_eigs(a: &mut [Vec<f64>]) -> Vec<f64> {
    let n = a.len();
    for _sweep in 0..100 {
        let mut off = 0.0;
        for i in 0..n {
            for j in 0..n {
                if i != j {
                    off += a[i][j] * a[i][j];
                }
            }
        }
        if off < 1e-22 {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                if a[p][q].abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let akp = a[k][p];
                    let akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let apk = a[p][k];
                    let aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
            }
        }
    }
    (0..n).map(|i| a[i][i]).collect()
}

fn check(
    n: usize,
    m: usize,
    hess: &[(usize, usize, f64)],
    jac: &[(usize, usize, f64)],
    backend: LdltBackend,
) {
    let hp: Vec<_> = hess.iter().map(|&(r, c, _)| (r, c)).collect();
    let jp: Vec<_> = jac.iter().map(|&(r, c, _)| (r, c)).collect();
    let hv: Vec<_> = hess.iter().map(|&(_, _, v)| v).collect();
    let jv: Vec<_> = jac.iter().map(|&(_, _, v)| v).collect();
    let mut pat = KktPattern::new(n, m, &hp, &jp);
    pat.assemble(&hv, &jv, &vec![0.0; n], -1e-9);
    let dim = n + m;
    let mut dense = vec![vec![0.0; dim]; dim];
    for j in 0..dim {
        for p in pat.mat.col_ptr[j]..pat.mat.col_ptr[j + 1] {
            let i = pat.mat.row_idx[p];
            dense[i][j] += pat.mat.values[p];
            if i != j {
                dense[j][i] += pat.mat.values[p];
            }
        }
    }
    let eig = dense_eigs(&mut dense.clone());
    let expect = eig_inertia(&eig);
    let mut s = SparseLdlt::with_backend(backend);
    s.analyse(dim, &pat.mat.col_ptr, &pat.mat.row_idx).unwrap();
    let inertia = s.factor(&pat.mat.values).expect("nonsingular");
    assert_eq!(inertia, expect, "{backend:?}");
    // Unpivoted LDLᵀ on an indefinite matrix loses a few digits; two refinement steps
    // (as the IPM does) recover them.
    let res = refined_residual(&mut s, &pat, 2);
    assert!(res < 1e-8, "residual {res}");
}

#[test]
fn inertia_matches_dense_eigenvalues() {
    // H indefinite 4x4 (tridiagonal), 2 constraints; both factor variants.
    let hess = vec![
        (0, 0, 2.0),
        (1, 1, -1.0),
        (2, 2, 3.0),
        (3, 3, 0.5),
        (1, 0, 0.3),
        (2, 1, 0.7),
        (3, 2, -0.2),
        (3, 3, 0.1), // duplicate entry: summed
    ];
    let jac = vec![
        (0, 0, 1.0),
        (0, 1, 2.0),
        (1, 2, 1.0),
        (1, 3, -1.0),
        (1, 1, 0.5),
    ];
    for backend in [
        LdltBackend::Auto,
        LdltBackend::FaerSupernodal,
        LdltBackend::Simplicial,
    ] {
        check(4, 2, &hess, &jac, backend);
    }
    // Larger banded system whose inertia changes with the diagonal shift.
    let n = 60;
    let m = 20;
    let mut hess = Vec::new();
    for i in 0..n {
        hess.push((
            i,
            i,
            if i % 7 == 0 {
                -2.0
            } else {
                4.0 + libm::cos(i as f64)
            },
        ));
        if i + 1 < n {
            hess.push((i + 1, i, 0.9));
        }
        if i + 5 < n {
            hess.push((i + 5, i, -0.4));
        }
    }
    let mut jac = Vec::new();
    for r in 0..m {
        for k in 0..4 {
            jac.push((
                r,
                (3 * r + k * 2) % n,
                1.0 + 0.1 * k as f64 + 0.01 * r as f64,
            ));
        }
    }
    for backend in [LdltBackend::FaerSupernodal, LdltBackend::Simplicial] {
        check(n, m, &hess, &jac, backend);
    }
}

/// The prepared simplicial path reproduces faer's own factorization and solve bit for bit
/// (inertia, every entry of L, the solution), including pivots hit by static pivoting and
/// indefinite diagonals, on a random sparse KKT of collocation-like size.
#[test]
fn prepared_simplicial_path_is_bitwise_faer() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let (n, m) = (300, 180);
    let mut hess = Vec::new();
    for i in 0..n {
        // every 9th variable has no curvature (zero diagonal → static pivoting)
        if i % 9 != 0 {
            hess.push((i, i, rng.random_range(-1.0..3.0)));
        }
        for _ in 0..2 {
            let j = rng.random_range(0..=i);
            hess.push((i, j, rng.random_range(-0.5..0.5)));
        }
    }
    let mut jac = Vec::new();
    for r in 0..m {
        for _ in 0..5 {
            jac.push((r, rng.random_range(0..n), rng.random_range(-2.0..2.0)));
        }
        jac.push((r, n - 1, 1.0)); // a dense column (like a phase duration)
    }
    let hp: Vec<_> = hess.iter().map(|&(r, c, _)| (r, c)).collect();
    let jp: Vec<_> = jac.iter().map(|&(r, c, _)| (r, c)).collect();
    let hv: Vec<_> = hess.iter().map(|&(_, _, v)| v).collect();
    let jv: Vec<_> = jac.iter().map(|&(_, _, v)| v).collect();
    let mut pat = KktPattern::new(n, m, &hp, &jp);
    let dim = n + m;
    let b: Vec<f64> = (0..dim).map(|i| libm::cos(i as f64 * 0.71)).collect();
    for shift in [0.0, 0.5, 10.0] {
        pat.assemble(&hv, &jv, &vec![shift; n], -1e-9);
        let mut out = Vec::new();
        for backend in [LdltBackend::Simplicial, LdltBackend::FaerSimplicial] {
            let mut s = SparseLdlt::with_backend(backend);
            s.analyse(dim, &pat.mat.col_ptr, &pat.mat.row_idx).unwrap();
            assert_eq!(
                matches!(s.kernel, Kernel::Simplicial(_)),
                backend == LdltBackend::Simplicial
            );
            let inertia = s.factor(&pat.mat.values);
            let mut x = b.clone();
            if inertia.is_ok() {
                s.solve(&mut x).unwrap();
            }
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            out.push((inertia, bits(&s.faer.as_ref().unwrap().l_values), bits(&x)));
        }
        assert!(out[0].0.is_ok(), "shift {shift}: factor failed");
        assert_eq!(out[0], out[1], "shift {shift}");
    }
}

/// Shape of a random block-banded KKT from [`banded_kkt`].
struct KktShape {
    /// Every `zero_diag_every`-th variable has no Hessian diagonal.
    zero_diag_every: usize,
    /// Size of the dense element blocks of `H`.
    block: usize,
    /// Probability of each off-diagonal entry inside a block.
    density: f64,
    /// Variables per constraint row (besides the dense last column).
    row_vars: usize,
    /// Spacing of a row's variables.
    stride: usize,
}

/// Random KKT-like matrix `[H + diag(diag_x), Jᵀ; J, −δ_c I]` with a block-banded indefinite
/// Hessian (dense element blocks, like collocation), some zero primal diagonals, constraint
/// rows of `shape.row_vars` variables each and a dense last column. Returns the pattern (values
/// assembled) and the dense matrix.
fn banded_kkt(
    seed: u64,
    (n, m): (usize, usize),
    shape: &KktShape,
    diag_x: &[f64],
    delta_c: f64,
) -> (KktPattern, Vec<Vec<f64>>) {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut hess = Vec::new();
    for i in 0..n {
        if i % shape.zero_diag_every != 0 {
            hess.push((i, i, rng.random_range(-1.0..3.0)));
        }
        for j in (i / shape.block) * shape.block..i {
            if rng.random_bool(shape.density) {
                hess.push((i, j, rng.random_range(-0.5..0.5)));
            }
        }
    }
    let mut jac = Vec::new();
    for r in 0..m {
        let base = (r * n) / m;
        for k in 0..shape.row_vars {
            jac.push((
                r,
                (base + k * shape.stride) % n,
                rng.random_range(-2.0..2.0),
            ));
        }
        jac.push((r, n - 1, 1.0));
    }
    let hp: Vec<_> = hess.iter().map(|&(r, c, _)| (r, c)).collect();
    let jp: Vec<_> = jac.iter().map(|&(r, c, _)| (r, c)).collect();
    let hv: Vec<_> = hess.iter().map(|&(_, _, v)| v).collect();
    let jv: Vec<_> = jac.iter().map(|&(_, _, v)| v).collect();
    let mut pat = KktPattern::new(n, m, &hp, &jp);
    pat.assemble(&hv, &jv, diag_x, -delta_c);
    let dim = n + m;
    let mut dense = vec![vec![0.0; dim]; dim];
    for j in 0..dim {
        for p in pat.mat.col_ptr[j]..pat.mat.col_ptr[j + 1] {
            let i = pat.mat.row_idx[p];
            dense[i][j] += pat.mat.values[p];
            if i != j {
                dense[j][i] += pat.mat.values[p];
            }
        }
    }
    (pat, dense)
}

/// Random KKT-like matrix `[H + shift I, Jᵀ; J, −1e-9 I]` ([`banded_kkt`] with element blocks of
/// 8 variables and rows of 6).
fn random_kkt(seed: u64, n: usize, m: usize, shift: f64) -> (KktPattern, Vec<Vec<f64>>) {
    let shape = KktShape {
        zero_diag_every: 7,
        block: 8,
        density: 0.7,
        row_vars: 6,
        stride: 3,
    };
    banded_kkt(seed, (n, m), &shape, &vec![shift; n], 1e-9)
}

/// The supernodal block kernel against independent computations on random indefinite
/// KKT-like matrices: `P K Pᵀ = L D Lᵀ` entrywise (with the static-pivot replacements
/// accounted for on the diagonal), inertia against Jacobi eigenvalues, the solution against
/// the residual, and the same inertia decision as the simplicial path.
#[test]
fn block_kernel_reconstructs_and_matches_dense_inertia() {
    for (seed, n, m, shift) in [
        (1, 40, 24, 0.0),
        (2, 40, 24, 1.0),
        (3, 90, 50, -0.3),
        (4, 90, 50, 5.0),
        (5, 120, 100, 0.0),
    ] {
        let (pat, dense) = random_kkt(seed, n, m, shift);
        let dim = n + m;
        let mut s = SparseLdlt::with_backend(LdltBackend::Supernodal);
        s.analyse(dim, &pat.mat.col_ptr, &pat.mat.row_idx).unwrap();
        let Kernel::Supernodal(blk) = &s.kernel else {
            panic!("block plan");
        };
        assert!(
            (0..blk.sn_begin.len() - 1).any(|k| blk.sn_begin[k + 1] - blk.sn_begin[k] > 2),
            "seed {seed}: test matrix has no multi-column supernode"
        );
        let inertia = s.factor(&pat.mat.values);
        let mut simp = SparseLdlt::with_backend(LdltBackend::Simplicial);
        simp.analyse(dim, &pat.mat.col_ptr, &pat.mat.row_idx)
            .unwrap();
        assert_eq!(inertia, simp.factor(&pat.mat.values), "seed {seed}");
        let inertia = inertia.expect("factor");
        let eig = dense_eigs(&mut dense.clone());
        let Kernel::Supernodal(blk) = &s.kernel else {
            unreachable!()
        };
        // Dense L (unit diagonal) and D in permuted order.
        let mut l = vec![vec![0.0; dim]; dim];
        for k in 0..blk.sn_begin.len() - 1 {
            let (f, e) = (blk.sn_begin[k], blk.sn_begin[k + 1]);
            let rows = &blk.sn_rows[blk.sn_row_ptr[k]..blk.sn_row_ptr[k + 1]];
            let nr = rows.len();
            for c in 0..e - f {
                l[f + c][f + c] = 1.0;
                for (pos, &r) in rows.iter().enumerate().skip(c + 1) {
                    l[r as usize][f + c] = blk.vals[blk.sn_val_ptr[k] + c * nr + pos];
                }
            }
        }
        // Componentwise backward error of an LDLᵀ: |P K Pᵀ − L D Lᵀ| ≤ c u (|L| |D| |Lᵀ|).
        let mut pivots_replaced = 0;
        let mut max_ratio = 0.0f64;
        for i in 0..dim {
            for j in 0..=i {
                let (mut ldl, mut bound) = (0.0, 0.0);
                for k in 0..=j {
                    ldl += l[i][k] * blk.d[k] * l[j][k];
                    bound += (l[i][k] * blk.d[k] * l[j][k]).abs();
                }
                let a = dense[blk.perm_fwd[i]][blk.perm_fwd[j]];
                let err = (ldl - a).abs();
                if i == j && err > 1e-9 {
                    // static pivot: the factor is of K + E with E diagonal, |E| ≤ δ + ε
                    assert!(
                        err <= s.options().pivot_delta + s.options().pivot_epsilon + 1e-12,
                        "{err}"
                    );
                    pivots_replaced += 1;
                } else if err > 0.0 {
                    max_ratio = max_ratio.max(err / bound);
                }
            }
        }
        assert!(max_ratio <= 1e-13, "seed {seed}: {max_ratio}");
        let expect = eig_inertia(&eig);
        if pivots_replaced == 0 {
            assert_eq!(inertia, expect, "seed {seed}");
        }
        let res = refined_residual(&mut s, &pat, 3);
        assert!(res < 1e-8, "seed {seed}: residual {res}");
    }
}

/// A structurally singular KKT (a variable in neither H nor J) is reported by the block
/// kernel when static pivoting is off, and the IPM-facing inertia has no zero count.
#[test]
fn block_kernel_reports_singular() {
    let (_, s) = singular_without_static_pivoting(LdltBackend::Supernodal);
    assert!(matches!(s.kernel, Kernel::Supernodal(_)));
}

/// The structurally singular KKT of the `…_reports_singular` tests (x1 is in neither H nor J),
/// analysed by `backend` with static pivoting off; asserts that the factorization reports it.
fn singular_without_static_pivoting(backend: LdltBackend) -> (KktPattern, SparseLdlt) {
    let mut pat = KktPattern::new(3, 1, &[(0, 0), (2, 0)], &[(0, 0), (0, 2)]);
    pat.assemble(&[1.0, 0.5], &[1.0, 2.0], &[0.0; 3], 0.0);
    let mut s = SparseLdlt::with_options(LdltOptions {
        backend,
        pivot_epsilon: 0.0,
        pivot_delta: 0.0,
        ..LdltOptions::default()
    });
    s.analyse(4, &pat.mat.col_ptr, &pat.mat.row_idx).unwrap();
    assert!(s.factor(&pat.mat.values).is_err(), "{backend:?}");
    (pat, s)
}

#[test]
fn singular_matrix_is_reported() {
    // x-block zero and no constraint coupling on variable 1: exact zero pivot.
    let mut pat = KktPattern::new(2, 1, &[], &[(0, 0)]);
    pat.assemble(&[], &[1.0], &[0.0, 0.0], 0.0);
    let mut s = SparseLdlt::with_options(LdltOptions {
        pivot_epsilon: 0.0,
        pivot_delta: 0.0,
        ..LdltOptions::default()
    });
    s.analyse(3, &pat.mat.col_ptr, &pat.mat.row_idx).unwrap();
    assert!(s.factor(&pat.mat.values).is_err());
}

/// Structurally zero primal diagonals (variables without curvature, like collocation states
/// without cost): static pivoting keeps the factorization alive, the inertia stays (n, m)
/// and iterative refinement recovers the exact solution.
#[test]
fn static_pivoting_with_zero_primal_diagonal() {
    // chain: x0 -(c0)- x1 -(c1)- x2, cost only on x2; n = 3, m = 2, H = diag(0, 0, 1)
    let hess = [(2, 2)];
    let jac = [(0, 0), (0, 1), (1, 1), (1, 2)];
    let mut pat = KktPattern::new(3, 2, &hess, &jac);
    pat.assemble(&[1.0], &[1.0, -1.0, 1.0, -1.0], &[0.0; 3], -1e-9);
    for backend in [LdltBackend::FaerSupernodal, LdltBackend::Simplicial] {
        let mut s = SparseLdlt::with_backend(backend);
        s.analyse(5, &pat.mat.col_ptr, &pat.mat.row_idx).unwrap();
        // With pivoting disabled the zero pivot (if eliminated first) would stop LDLᵀ;
        // with it the factor exists and has the KKT inertia.
        let inertia = s.factor(&pat.mat.values).expect("factor");
        assert_eq!(
            inertia,
            Inertia {
                positive: 3,
                negative: 2,
                zero: 0
            }
        );
        let b = [1.0, -2.0, 0.5, 0.3, -0.7];
        let mut x = b;
        s.solve(&mut x).unwrap();
        let mut r = [0.0; 5];
        for _ in 0..5 {
            pat.mat.sym_matvec(&x, &mut r);
            let mut c: Vec<f64> = b.iter().zip(&r).map(|(b, r)| b - r).collect();
            s.solve(&mut c).unwrap();
            for i in 0..5 {
                x[i] += c[i];
            }
        }
        pat.mat.sym_matvec(&x, &mut r);
        let res = r
            .iter()
            .zip(&b)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(res < 1e-12, "refined residual {res}");
    }
}

/// AMD's order with 2 × 2 (variable, constraint row) pivots against independent computations
/// on random indefinite KKT-like matrices: every constraint row is either in a pair with a
/// primal neighbour of its own or preceded by an unpaired primal neighbour (no bare −δ_c
/// pivot), `P K Pᵀ = L D Lᵀ` entrywise with `D` block diagonal, the inertia against Jacobi
/// eigenvalues and the refined solution against the residual.
#[test]
fn pivot_pairs_reconstruct_and_match_dense_inertia() {
    for (seed, n, m, shift) in [
        (1, 40, 24, 0.0),
        (2, 40, 24, 1.0),
        (3, 90, 50, -0.3),
        (4, 90, 50, 5.0),
        (5, 120, 100, 0.0),
        (6, 60, 55, 0.5),
    ] {
        let (pat, dense) = random_kkt(seed, n, m, shift);
        let dim = n + m;
        let mut s = SparseLdlt::with_options(LdltOptions {
            ordering: LdltOrdering::AmdPivotPairs {
                constraint_rows_from: n,
            },
            ..LdltOptions::default()
        });
        s.analyse(dim, &pat.mat.col_ptr, &pat.mat.row_idx).unwrap();
        let inertia = s.factor(&pat.mat.values).expect("factor");
        let Kernel::Supernodal(blk) = &s.kernel else {
            panic!("seed {seed}: pivot pairs need the block kernel");
        };
        let npairs = blk.pair.iter().filter(|&&p| p).count();
        assert!(npairs > 0, "seed {seed}: no pair formed");
        // Dense L (unit diagonal, L[j + 1, j] = 0 in a pair) and block-diagonal D.
        let mut l = vec![vec![0.0; dim]; dim];
        let mut stored = vec![vec![false; dim]; dim];
        let mut d = vec![vec![0.0; dim]; dim];
        for k in 0..blk.sn_begin.len() - 1 {
            let (f, e) = (blk.sn_begin[k], blk.sn_begin[k + 1]);
            let rows = &blk.sn_rows[blk.sn_row_ptr[k]..blk.sn_row_ptr[k + 1]];
            let nr = rows.len();
            for c in 0..e - f {
                l[f + c][f + c] = 1.0;
                for (pos, &r) in rows.iter().enumerate().skip(c + 1) {
                    l[r as usize][f + c] = blk.vals[blk.sn_val_ptr[k] + c * nr + pos];
                    stored[r as usize][f + c] = true;
                }
            }
        }
        // Structure: a pair is (variable, row); a row outside a pair has a primal variable
        // eliminated before it as a 1 × 1 pivot in its row of L (so its pivot is not −δ_c).
        for k in 0..dim {
            let r = blk.perm_fwd[k];
            if blk.pair[k] {
                assert!(
                    r < n && blk.perm_fwd[k + 1] >= n,
                    "seed {seed}: pair at {k}"
                );
            }
            if r < n || (k > 0 && blk.pair[k - 1]) {
                continue;
            }
            let ok = (0..k).any(|j| stored[k][j] && blk.perm_fwd[j] < n && !blk.pair[j]);
            assert!(ok, "seed {seed}: row {r} has a bare pivot");
        }
        for j in 0..dim {
            d[j][j] = blk.d[j];
            if blk.pair[j] {
                assert_eq!(l[j + 1][j], 0.0);
                d[j][j + 1] = blk.e[j];
                d[j + 1][j] = blk.e[j];
            }
        }
        // L D and |L| |D| (the componentwise bound |L| |D| |Lᵀ| of the backward error).
        let mut ld = vec![vec![0.0; dim]; dim];
        let mut ld_abs = vec![vec![0.0; dim]; dim];
        for i in 0..dim {
            for k in 0..dim {
                if l[i][k] != 0.0 {
                    for j in k.saturating_sub(1)..(k + 2).min(dim) {
                        ld[i][j] += l[i][k] * d[k][j];
                        ld_abs[i][j] += (l[i][k] * d[k][j]).abs();
                    }
                }
            }
        }
        let mut pivots_replaced = 0;
        let mut max_ratio = 0.0f64;
        for i in 0..dim {
            for j in 0..=i {
                let (mut ldl, mut bound) = (0.0, 0.0);
                for k in 0..dim {
                    ldl += ld[i][k] * l[j][k];
                    bound += ld_abs[i][k] * l[j][k].abs();
                }
                let a = dense[blk.perm_fwd[i]][blk.perm_fwd[j]];
                let err = (ldl - a).abs();
                if i == j && err > 1e-9 {
                    assert!(
                        err <= s.options().pivot_delta + s.options().pivot_epsilon + 1e-12,
                        "{err}"
                    );
                    pivots_replaced += 1;
                } else if blk.pair[j] && i == j + 1 && blk.e[j] == 0.0 {
                    // a pair's coupling below `pivot_epsilon` is dropped (two 1 × 1 pivots)
                    assert!(err <= s.options().pivot_epsilon, "{err}");
                } else if err > 0.0 {
                    max_ratio = max_ratio.max(err / bound);
                }
            }
        }
        assert!(
            max_ratio <= 1e-13,
            "seed {seed}: {npairs} pairs, {max_ratio}"
        );
        let eig = dense_eigs(&mut dense.clone());
        let expect = eig_inertia(&eig);
        if pivots_replaced == 0 {
            assert_eq!(inertia, expect, "seed {seed}");
        }
        let res = refined_residual(&mut s, &pat, 3);
        assert!(res < 1e-8, "seed {seed}: residual {res}");
    }
}

/// The numeric phase reports why it has no factor, as data, and a solve after a failed
/// factorization refuses instead of using a stale factor.
#[test]
fn factorization_failures_are_typed() {
    let mut pat = KktPattern::new(2, 1, &[(0, 0), (1, 1)], &[(0, 0)]);
    pat.assemble(&[2.0, 3.0], &[1.0], &[0.0, 0.0], -1e-9);
    let mut s = SparseLdlt::new();
    assert_eq!(
        s.factor(&pat.mat.values),
        Err(FactorizationFailure::NotAnalysed)
    );
    let mut rhs = vec![1.0, 2.0, 3.0];
    assert_eq!(s.solve(&mut rhs), Err(FactorizationFailure::NotAnalysed));
    s.analyse(3, &pat.mat.col_ptr, &pat.mat.row_idx).unwrap();
    let nnz = pat.mat.values.len();
    assert_eq!(
        s.factor(&pat.mat.values[..nnz - 1]),
        Err(FactorizationFailure::ValueCount {
            expected: nnz,
            got: nnz - 1
        })
    );
    let good = s.factor(&pat.mat.values).unwrap();
    assert_eq!((good.positive, good.negative, good.zero), (2, 1, 0));
    // K x = b for K = [2 0 1; 0 3 0; 1 0 −1e-9]: x₂ = 2/3 and 2x₁ + x₃ = 1, x₁ ≈ 3.
    s.solve(&mut rhs).unwrap();
    assert!((rhs[1] - 2.0 / 3.0).abs() < 1e-12);
    assert!((2.0 * rhs[0] + rhs[2] - 1.0).abs() < 1e-9);
    let mut bad = pat.mat.values.clone();
    bad[1] = f64::NAN;
    assert_eq!(
        s.factor(&bad),
        Err(FactorizationFailure::NonFiniteValue { index: 1 })
    );
    let mut rhs = vec![1.0, 2.0, 3.0];
    assert!(s.solve(&mut rhs).is_err());
    assert_eq!(rhs, [1.0, 2.0, 3.0], "a refused solve leaves rhs as it was");
    // The same solver factors again after the failure.
    assert_eq!(s.factor(&pat.mat.values), Ok(good));
}

/// The public KKT API refuses malformed input with an error instead of panicking: triplets of
/// [`KktPattern::try_new`] out of range or above the diagonal, CSC patterns that faer's
/// analysis would assert on or the kernels would index out of range, an elimination order that
/// is no permutation, and a right-hand side of the wrong length. A refused pattern leaves the
/// solver without an analysis, so no stale factor is used.
#[test]
fn malformed_kkt_input_is_an_error() {
    let pattern = |what, index, row, col| OptimError::InvalidPattern {
        what,
        index,
        row,
        col,
    };
    assert_eq!(
        KktPattern::try_new(2, 1, &[(0, 0), (2, 0)], &[]).err(),
        Some(pattern("hessian", 1, 2, 0))
    );
    assert_eq!(
        KktPattern::try_new(2, 1, &[(0, 1)], &[]).err(),
        Some(pattern("hessian", 0, 0, 1))
    );
    assert_eq!(
        KktPattern::try_new(2, 1, &[], &[(0, 0), (1, 0)]).err(),
        Some(pattern("jacobian", 1, 1, 0))
    );
    assert_eq!(
        KktPattern::try_new(2, 1, &[], &[(0, 2)]).err(),
        Some(pattern("jacobian", 0, 0, 2))
    );
    let pat = KktPattern::new(2, 1, &[(0, 0), (1, 1)], &[(0, 0)]);
    let same = KktPattern::try_new(2, 1, &[(0, 0), (1, 1)], &[(0, 0)]).unwrap();
    assert_eq!(
        (&same.mat.col_ptr, &same.mat.row_idx),
        (&pat.mat.col_ptr, &pat.mat.row_idx)
    );
    // K = [2 0 1; 0 3 0; 1 0 −1e-9]: columns {0, 2}, {1}, {2}.
    let mut pat = pat;
    pat.assemble(&[2.0, 3.0], &[1.0], &[0.0, 0.0], -1e-9);
    let (cp, ri) = (&pat.mat.col_ptr[..], &pat.mat.row_idx[..]);
    assert_eq!((cp, ri), (&[0, 2, 3, 4][..], &[0, 2, 1, 2][..]));
    let pointers = |index, value| OptimError::InvalidColumnPointers {
        index,
        value,
        entries: 4,
    };
    let cases: Vec<(usize, Vec<usize>, Vec<usize>, OptimError)> = vec![
        (
            3,
            vec![],
            ri.to_vec(),
            OptimError::DimensionMismatch {
                what: "KKT column pointers",
                expected: 4,
                found: 0,
            },
        ),
        (
            2,
            cp.to_vec(),
            ri.to_vec(),
            OptimError::DimensionMismatch {
                what: "KKT column pointers",
                expected: 3,
                found: 4,
            },
        ),
        (3, vec![1, 2, 3, 4], ri.to_vec(), pointers(0, 1)),
        (3, vec![0, 3, 2, 4], ri.to_vec(), pointers(2, 2)),
        (3, vec![0, 2, 3, 5], ri.to_vec(), pointers(3, 5)),
        (3, vec![0, 2, 3, 3], ri.to_vec(), pointers(3, 3)),
        (3, cp.to_vec(), vec![0, 3, 1, 2], pattern("kkt", 1, 3, 0)),
        (3, cp.to_vec(), vec![0, 2, 0, 2], pattern("kkt", 2, 0, 1)),
        (3, cp.to_vec(), vec![2, 0, 1, 2], pattern("kkt", 1, 0, 0)),
        (3, cp.to_vec(), vec![0, 0, 1, 2], pattern("kkt", 1, 0, 0)),
    ];
    for backend in [LdltBackend::Auto, LdltBackend::Multifrontal] {
        for (dim, cp_bad, ri_bad, expected) in &cases {
            let mut s = SparseLdlt::with_backend(backend);
            s.analyse(3, cp, ri).unwrap();
            assert_eq!(
                s.analyse(*dim, cp_bad, ri_bad),
                Err(expected.clone()),
                "{cp_bad:?} {ri_bad:?}"
            );
            assert_eq!(
                s.factor(&pat.mat.values),
                Err(FactorizationFailure::NotAnalysed)
            );
        }
    }
    // A diagonal entry need not be stored (it is then 0, as the kernels take it): here
    // [0 1; 1 2], inertia (1, 1).
    let mut s = SparseLdlt::new();
    s.analyse(2, &[0, 1, 2], &[1, 1]).unwrap();
    let inertia = s.factor(&[1.0, 2.0]).unwrap();
    assert_eq!((inertia.positive, inertia.negative), (1, 1));
    // An order that is no permutation of 0..dim is not taken: the pattern is ordered anew.
    let pairs = LdltOptions {
        ordering: LdltOrdering::AmdPivotPairs {
            constraint_rows_from: 2,
        },
        ..LdltOptions::default()
    };
    for amd in [&[0, 0, 1][..], &[0, 1, 3], &[2, 1, 0, 3]] {
        let mut s = SparseLdlt::with_options(pairs.clone());
        s.analyse_in_amd_order(3, cp, ri, Some(amd)).unwrap();
        let inertia = s.factor(&pat.mat.values).unwrap();
        assert_eq!((inertia.positive, inertia.negative), (2, 1), "{amd:?}");
    }
    // A right-hand side of the wrong length is refused and left as it was.
    let mut s = SparseLdlt::new();
    s.analyse(3, cp, ri).unwrap();
    s.factor(&pat.mat.values).unwrap();
    for len in [2, 4] {
        let mut rhs = vec![1.0; len];
        assert_eq!(
            s.solve(&mut rhs),
            Err(FactorizationFailure::RhsLength {
                expected: 3,
                got: len
            })
        );
        assert_eq!(rhs, vec![1.0; len]);
    }
    let mut rhs = vec![1.0, 2.0, 3.0];
    s.solve(&mut rhs).unwrap();
    assert!((rhs[1] - 2.0 / 3.0).abs() < 1e-12);
}

/// `KktPattern::new` panics on the triplets `try_new` refuses, with the error's message.
#[test]
#[should_panic(expected = "invalid sparsity pattern in hessian: entry 0 = (0, 1)")]
fn a_kkt_pattern_above_the_diagonal_panics_in_new() {
    let _ = KktPattern::new(2, 0, &[(0, 1)], &[]);
}

/// A solver that returns to a pattern it analysed before takes the kept analysis instead of
/// analysing again, and factors and solves with it bit for bit as a new solver does; beyond
/// [`KEPT_ANALYSES`] other patterns, the oldest is analysed again. Every backend that keeps
/// per-pattern workspaces (the simplicial, supernodal and multifrontal plans) and the pivot
/// pairs' ordering are covered.
#[test]
fn a_pattern_analysed_before_is_taken_back_bit_for_bit() {
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    // Factor and solve with `s` (analysed for `pat`): the inertia and the solution's bits.
    let run = |s: &mut SparseLdlt, pat: &KktPattern| {
        let dim = pat.mat.col_ptr.len() - 1;
        s.analyse(dim, &pat.mat.col_ptr, &pat.mat.row_idx).unwrap();
        let inertia = s.factor(&pat.mat.values);
        let mut x: Vec<f64> = (0..dim).map(|i| libm::sin(i as f64 * 0.37)).collect();
        s.solve(&mut x).unwrap();
        (inertia, bits(&x))
    };
    let patterns: Vec<KktPattern> = (0..KEPT_ANALYSES + 2)
        .map(|k| random_kkt(40 + k as u64, 60 + 7 * k, 30 + 3 * k, 0.5).0)
        .collect();
    for options in [
        LdltOptions::default(),
        LdltOptions {
            backend: LdltBackend::Supernodal,
            ..LdltOptions::default()
        },
        LdltOptions {
            backend: LdltBackend::Multifrontal,
            ..LdltOptions::default()
        },
    ] {
        let fresh = |pat: &KktPattern| run(&mut SparseLdlt::with_options(options.clone()), pat);
        let mut s = SparseLdlt::with_options(options.clone());
        // A, B, A: the second A is the kept analysis, with a dirty workspace from B.
        let first = run(&mut s, &patterns[0]);
        let _ = run(&mut s, &patterns[1]);
        let again = run(&mut s, &patterns[0]);
        assert_eq!(s.analyses(), 2, "{options:?}");
        assert_eq!(first, again, "{options:?}");
        assert_eq!(again, fresh(&patterns[0]), "{options:?}");
        // Every other pattern once more: pattern 0 drops out of the kept ones.
        for pat in &patterns[1..] {
            assert_eq!(run(&mut s, pat), fresh(pat), "{options:?}");
        }
        assert_eq!(s.analyses(), patterns.len(), "{options:?}");
        assert_eq!(run(&mut s, &patterns[0]), first, "{options:?}");
        assert_eq!(s.analyses(), patterns.len() + 1, "{options:?}");
    }
    // The pivot pairs' order (its options depend on the number of variables, as in
    // `Core::try_pivot_pairs`): one solver per `n`, patterns of that `n` kept.
    let pairs = |seed| random_kkt(seed, 80, 40, 0.5).0;
    let options = LdltOptions {
        ordering: LdltOrdering::AmdPivotPairs {
            constraint_rows_from: 80,
        },
        ..LdltOptions::default()
    };
    let (a, b) = (pairs(1), pairs(2));
    let mut s = SparseLdlt::with_options(options.clone());
    let first = run(&mut s, &a);
    let _ = run(&mut s, &b);
    assert_eq!(run(&mut s, &a), first);
    assert_eq!(s.analyses(), 2);
    assert_eq!(first, run(&mut SparseLdlt::with_options(options), &a));
}

/// The supernodal kernel with its large supernodes shared between two threads gives the
/// factor of one thread bit for bit (the same operations per entry in the same order), with
/// and without 2 × 2 pivot pairs, on KKTs whose dense element blocks make supernodes wide
/// enough to be shared (both the descendant updates and the own columns' panels).
#[test]
fn a_factor_shared_between_two_threads_is_the_factor_of_one() {
    let shape = KktShape {
        zero_diag_every: 5,
        block: 240,
        density: 0.9,
        row_vars: 60,
        stride: 2,
    };
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    for (seed, pairs) in [(11, false), (12, true), (13, true)] {
        let (n, m) = (720, 300);
        let (pat, _) = banded_kkt(seed, (n, m), &shape, &vec![0.5; n], 1e-9);
        let ordering = if pairs {
            LdltOrdering::AmdPivotPairs {
                constraint_rows_from: n,
            }
        } else {
            LdltOrdering::Amd
        };
        let mut s = SparseLdlt::with_options(LdltOptions {
            backend: LdltBackend::Supernodal,
            ordering,
            ..LdltOptions::default()
        });
        s.analyse(n + m, &pat.mat.col_ptr, &pat.mat.row_idx)
            .unwrap();
        let bits = |s: &SparseLdlt| {
            let Kernel::Supernodal(b) = &s.kernel else {
                panic!("seed {seed}: the supernodal kernel");
            };
            let words = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            let w = (words(&b.d), words(&b.e), words(&b.inv_d), words(&b.inv_e));
            (words(&b.l), w)
        };
        {
            let Kernel::Supernodal(b) = &s.kernel else {
                panic!("seed {seed}: the supernodal kernel");
            };
            assert!(
                b.sn_split.iter().any(|&c| c > 0),
                "seed {seed}: no split updates"
            );
            let paneled = |with_pair: bool| {
                (0..b.sn_panels.len()).any(|k| b.sn_panels[k] && b.sn_pair[k] == with_pair)
            };
            assert!(paneled(pairs), "seed {seed}: no panels (pairs: {pairs})");
            if cores >= 2 {
                assert!(b.shares_work(), "seed {seed}: nothing to share");
            }
        }
        let one = s.factor_numeric(&pat.mat.values, false).expect("factor");
        let one_bits = bits(&s);
        s.last = s.factor_numeric(&pat.mat.values, true);
        let two = s.last.expect("factor");
        assert_eq!(one, two, "seed {seed}: inertia");
        assert!(one_bits == bits(&s), "seed {seed}: the factors differ");
        assert!(
            refined_residual(&mut s, &pat, 3) < 1e-10,
            "seed {seed}: the shared factor solves K"
        );
        // Three threads sharing at once (the pool's one worker serves them all).
        std::thread::scope(|scope| {
            for _ in 0..3 {
                let mut copy = s.duplicate().expect("a copy");
                let (values, want) = (&pat.mat.values, &one_bits);
                scope.spawn(move || {
                    for _ in 0..4 {
                        copy.last = copy.factor_numeric(values, true);
                        assert_eq!(copy.last, Ok(one), "seed {seed}: inertia at once");
                        assert!(*want == bits(&copy), "seed {seed}: a factor at once");
                    }
                });
            }
        });
        // A factorization that stops at a non-finite pivot in a shared supernode returns
        // the failure, as on one thread, and leaves the helper free for the next.
        let mut bad = pat.mat.values.clone();
        let last = *pat.mat.col_ptr.last().expect("columns") - 1;
        bad[last] = f64::NAN;
        let alone = s.factor_numeric(&bad, false);
        assert!(alone.is_err(), "seed {seed}: a NaN factored");
        assert_eq!(
            s.factor_numeric(&bad, true),
            alone,
            "seed {seed}: the failure"
        );
        assert_eq!(
            s.factor_numeric(&pat.mat.values, true),
            Ok(one),
            "seed {seed}"
        );
        assert!(
            one_bits == bits(&s),
            "seed {seed}: the factor after a failure"
        );
    }
}

/// A dense symmetric matrix of entries uniform in [−1, 1), `diag(j)` added to the diagonal:
/// its lower triangle as CSC `(col_ptr, row_idx, values)` and the whole matrix by rows.
#[allow(clippy::type_complexity)]
fn dense_lower(
    dim: usize,
    rng: &mut impl rand::Rng,
    diag: impl Fn(usize) -> f64,
) -> (Vec<usize>, Vec<usize>, Vec<f64>, Vec<Vec<f64>>) {
    let (mut col_ptr, mut row_idx, mut values) = (vec![0], Vec::new(), Vec::new());
    let mut dense = vec![vec![0.0; dim]; dim];
    for j in 0..dim {
        for i in j..dim {
            let v: f64 = rng.random_range(-1.0..1.0) + if i == j { diag(j) } else { 0.0 };
            row_idx.push(i);
            values.push(v);
            dense[i][j] = v;
            dense[j][i] = v;
        }
        col_ptr.push(row_idx.len());
    }
    (col_ptr, row_idx, values, dense)
}

/// `max |K x − b|` for the plan's solution `x` of `K x = b` (`K` = `dense`, `b_i = sin i`).
fn dense_residual(plan: &mut BlockPlan, dense: &[Vec<f64>]) -> f64 {
    let b: Vec<f64> = (0..dense.len()).map(|i| libm::sin(i as f64)).collect();
    let mut x = b.clone();
    plan.solve(&mut x);
    dense
        .iter()
        .zip(&b)
        .map(|(row, bi)| (row.iter().zip(&x).map(|(a, x)| a * x).sum::<f64>() - bi).abs())
        .fold(0.0, f64::max)
}

/// A 2 × 2 pivot where a panel of the fixed width would end (the panels step over it, so that
/// no pivot is cut): one dense supernode of 200 columns whose pairs start at odd columns
/// (3, 7, 11, …: (15, 16) sits on the first panel's end), factored shared and on one thread,
/// bit for bit the same, and `L D Lᵀ` reproduces the matrix.
#[test]
fn a_pair_on_a_panel_end_is_stepped_over() {
    use rand::SeedableRng;
    let dim = 200;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let (col_ptr, row_idx, values, dense) = dense_lower(dim, &mut rng, |_| 0.3);
    let mut s = SparseLdlt::with_backend(LdltBackend::Supernodal);
    s.analyse(dim, &col_ptr, &row_idx).unwrap();
    let sym = &s.faer.as_ref().expect("analysed").symbolic;
    let pair_first: Vec<bool> = (0..dim).map(|j| j % 4 == 3 && j + 1 < dim).collect();
    let mut plan = BlockPlan::new(sym, dim, &col_ptr, &row_idx, &pair_first).expect("a plan");
    assert_eq!(plan.sn_begin.len(), 2, "one supernode");
    assert!(plan.sn_panels[0], "factored in panels");
    let cut = (0..dim - 1).filter(|&j| plan.pair[j] && (j + 1) % supernodal::PANEL == 0);
    assert!(cut.count() > 1, "pairs on the panels' ends");
    let words = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let bits = |p: &BlockPlan| {
        let w = (words(&p.d), words(&p.e), words(&p.inv_d), words(&p.inv_e));
        (words(&p.l), w)
    };
    let one = plan.factor(&values, 0.0, 0.0, false).expect("a factor");
    let one_bits = bits(&plan);
    let two = plan.factor(&values, 0.0, 0.0, true).expect("a factor");
    assert_eq!(one, two);
    assert!(one_bits == bits(&plan), "the factors differ");
    // L D Lᵀ against the permuted matrix: solve K x = b and check the residual.
    let res = dense_residual(&mut plan, &dense);
    assert!(res < 1e-8, "residual {res}");
}

/// A stretch of supernodes divided into two ranges that two threads factor at once gives the
/// factor of one thread bit for bit. The matrix: two dense blocks (a shared supernode each),
/// then two banded halves, the first depending on the first dense block and the second on the
/// second (eliminated in that order), then a few coupling rows; pivots of both signs. The
/// halves form the divided stretch, each of whose ranges reads a dense block's finished factor,
/// with 2 × 2 pivots in the dense blocks and in both halves. On two cores the pair must have
/// run on two threads. A NaN in a dense block, in either half or in the coupling block fails
/// as on one thread.
#[test]
fn a_stretch_divided_between_two_threads_is_the_factor_of_one() {
    use super::faer::FaerFactor;
    use super::supernodal::BlockPlan;
    use ::faer::sparse::linalg::SupernodalThreshold;
    use rand::{Rng, SeedableRng};
    let (dense, half, band, coupling) = (120, 400, 12, 16);
    let dim = 2 * dense + 2 * half + coupling;
    let (first, second, last) = (2 * dense, 2 * dense + half, 2 * dense + 2 * half);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
    let mut cols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); dim];
    for j in 0..dim {
        let sign = if j % 7 == 3 { -1.0 } else { 1.0 };
        let size = if j < first { dense } else { band };
        cols[j].push((j, sign * (size as f64 + rng.random_range(1.0..2.0))));
    }
    for (block, start) in [(0, first), (dense, second)] {
        for j in block..block + dense {
            for i in (j + 1..block + dense).chain(start..start + 3) {
                cols[j].push((i, rng.random_range(-0.5..0.5)));
            }
        }
    }
    for start in [first, second] {
        for i in start..start + half {
            for j in i.saturating_sub(band).max(start)..i {
                cols[j].push((i, rng.random_range(-0.5..0.5)));
            }
            if i % 29 == 0 {
                cols[i].push((last + (i / 29) % coupling, rng.random_range(-0.5..0.5)));
            }
        }
    }
    for j in last..dim {
        for i in j + 1..dim {
            cols[j].push((i, rng.random_range(-0.5..0.5)));
        }
    }
    let (mut col_ptr, mut row_idx, mut values) = (vec![0], Vec::new(), Vec::new());
    for c in &mut cols {
        c.sort_by_key(|&(i, _)| i);
        row_idx.extend(c.iter().map(|&(i, _)| i));
        values.extend(c.iter().map(|&(_, v)| v));
        col_ptr.push(row_idx.len());
    }
    let natural: Vec<usize> = (0..dim).collect();
    let ff = FaerFactor::analyse(
        dim,
        &col_ptr,
        &row_idx,
        SupernodalThreshold::FORCE_SIMPLICIAL,
        Some(&natural),
    )
    .expect("analysis");
    // 2 × 2 pivots asked for everywhere (granted where L[j + 1, j] is structurally nonzero).
    let pair_first: Vec<bool> = (0..dim).map(|j| j % 5 == 1).collect();
    let mut plan = BlockPlan::new(&ff.symbolic, dim, &col_ptr, &row_idx, &pair_first)
        .expect("a supernodal plan");
    for (name, range) in [("first", first..second), ("second", second..last)] {
        assert!(
            plan.pair[range].iter().any(|&p| p),
            "2 × 2 pivots in the {name} half"
        );
    }
    assert_eq!(
        plan.sn_begin[1..3],
        [dense, first],
        "the dense blocks' supernodes"
    );
    assert!(
        plan.sn_panels[0] && plan.sn_panels[1],
        "the dense blocks are shared"
    );
    let &[(s, x, y)] = plan.pairs.as_slice() else {
        panic!("one divided stretch, not {:?}", plan.pairs);
    };
    let columns = [s, x, y].map(|k| plan.sn_begin[k]);
    assert_eq!(
        columns[0], first,
        "the stretch starts after the dense blocks"
    );
    assert!(
        (second - band..=second).contains(&columns[1]),
        "the ranges meet at column {}, not at the halves' boundary {second}",
        columns[1]
    );
    assert_eq!(
        columns[2], last,
        "the second range ends where the coupling starts"
    );
    let words = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let bits = |p: &BlockPlan| {
        let pivots = (words(&p.d), words(&p.inv_d), words(&p.e), words(&p.inv_e));
        (words(&p.l), pivots)
    };
    let one = plan.factor(&values, 1e-12, 0.0, false).expect("factor");
    assert_eq!(one.negative, (0..dim).filter(|j| j % 7 == 3).count());
    let one_bits = bits(&plan);
    // On two cores the pair must run on two threads at least once: another test's
    // factorization may hold the helper for a moment, and then this one factors alone.
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    assert_eq!(plan.shares_work(), cores >= 2);
    let mut tries = 0;
    while tries < 3 || (cores >= 2 && plan.pairs_run == 0 && tries < 200) {
        let two = plan.factor(&values, 1e-12, 0.0, true).expect("factor");
        assert_eq!(one, two, "inertia");
        assert!(one_bits == bits(&plan), "the factors differ");
        tries += 1;
    }
    assert!(
        cores < 2 || plan.pairs_run > 0,
        "the pair never ran on two threads"
    );
    for j in [7, dense + 7, first + 7, second + 7, dim - 1] {
        let at = col_ptr[j];
        let mut bad = values.clone();
        bad[at] = f64::NAN;
        assert!(
            plan.factor(&bad, 1e-12, 0.0, false).is_none(),
            "a NaN factored"
        );
        assert!(
            plan.factor(&bad, 1e-12, 0.0, true).is_none(),
            "a NaN factored"
        );
    }
    assert_eq!(plan.factor(&values, 1e-12, 0.0, true), Some(one));
    assert!(one_bits == bits(&plan), "the factor after a failure");
}

/// The backward solve's sum over a column of `L` reads the column's leading run of
/// consecutive rows as a slice of `x` (decision record 0092): for every length and run, the
/// same bits as gathering every row (`head` 0, the sum before it), and the dot product to
/// rounding.
#[test]
fn a_column_sum_over_a_run_of_rows_is_the_gathered_sum() {
    use super::supernodal::dot_gather4;
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(92);
    let x: Vec<f64> = (0..200).map(|_| rng.random_range(-1.0..1.0)).collect();
    for len in 0..24usize {
        for run in 0..=len {
            let start: u32 = rng.random_range(0..50);
            let mut rows: Vec<u32> = (0..run as u32).map(|k| start + k).collect();
            let mut r = start + run as u32;
            while rows.len() < len {
                r += rng.random_range(2..5);
                rows.push(r);
            }
            let vals: Vec<f64> = (0..len)
                .map(|_| rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-6..6)))
                .collect();
            let gathered = dot_gather4(&vals, &rows, 0, &x);
            let sliced = dot_gather4(&vals, &rows, run, &x);
            assert_eq!(gathered.to_bits(), sliced.to_bits(), "len {len}, run {run}");
            let exact: f64 = vals
                .iter()
                .zip(&rows)
                .map(|(v, &r)| v * x[r as usize])
                .sum();
            let scale: f64 = vals
                .iter()
                .zip(&rows)
                .map(|(v, &r)| (v * x[r as usize]).abs())
                .sum();
            assert!(
                (sliced - exact).abs() <= 1e-14 * scale.max(1e-300),
                "len {len}, run {run}"
            );
        }
    }
}

/// The tiled descendant updates (decision record 0093) give every entry the operations of the
/// column-by-column updates in their order: a one-column descendant's update of 2 or 4
/// target columns at once is the same bits as one [`scatter_sub`] per column, and the sums of
/// 2 or 4 columns at once are those of one [`lincomb_sub`] per column, for every length and
/// number of source columns (chunks of four and the rest).
#[test]
fn target_columns_updated_together_are_updated_as_one_by_one() {
    use super::simplicial::scatter_sub;
    use super::supernodal::{lincomb_sub, lincomb_sub_stair, rank1_scatter};
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(93);
    let mut value = || rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-8..8));
    fn check_rank1<const G: usize>(len: usize, value: &mut impl FnMut() -> f64, seed: u64) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let nr = 2 * len + 3;
        // The descendant's rows: the first G are target columns of the block (base 5).
        let mut rows: Vec<u32> = Vec::new();
        let mut r = 5u32;
        for _ in 0..G {
            r += rng.random_range(1..3);
            rows.push(r);
        }
        let ncols = (r - 5 + 1) as usize;
        let mut rel: Vec<u32> = (0..len as u32).map(|k| 2 * k).collect();
        for x in rel.iter_mut() {
            *x += rng.random_range(0..2);
        }
        let v: Vec<f64> = (0..len).map(|_| value()).collect();
        let d = value();
        let blk0: Vec<f64> = (0..ncols * nr).map(|_| value()).collect();
        let mut tiled = blk0.clone();
        rank1_scatter::<G>(&mut tiled, nr, &rows, 5, &rel, &v, d);
        let mut single = blk0;
        for j in 0..G {
            let c = rows[j] as usize - 5;
            let sc = v[j] * d;
            scatter_sub(
                &mut single[c * nr..(c + 1) * nr],
                &rel[j..],
                &v[j..],
                sc,
                |r| r as usize,
            );
        }
        let bits = |a: &[f64]| a.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&tiled), bits(&single), "G {G}, {len} rows");
    }
    fn check_stair<const G: usize>(len: usize, wd: usize, value: &mut impl FnMut() -> f64) {
        let stride = len + G + 3;
        let off = 2;
        let blk: Vec<f64> = (0..wd * stride).map(|_| value()).collect();
        let coefs: Vec<f64> = (0..G * wd).map(|_| value()).collect();
        let outs0: Vec<Vec<f64>> = (0..G)
            .map(|j| (0..len + G - j).map(|_| value()).collect())
            .collect();
        let mut tiled = outs0.clone();
        {
            let mut it = tiled.iter_mut();
            let mut outs: [&mut [f64]; G] =
                std::array::from_fn(|_| it.next().map(|o| o.as_mut_slice()).unwrap_or_default());
            lincomb_sub_stair(&mut outs, &blk, stride, off, &coefs);
        }
        let mut single = outs0;
        for (j, out) in single.iter_mut().enumerate() {
            lincomb_sub(out, &blk, stride, off + j, &coefs[j * wd..(j + 1) * wd]);
        }
        for (t, s) in tiled.iter().zip(&single) {
            let bits = |a: &[f64]| a.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(t), bits(s), "G {G}, {len} rows, {wd} source columns");
        }
    }
    for len in 4..20 {
        check_rank1::<2>(len, &mut value, len as u64);
        check_rank1::<4>(len, &mut value, 100 + len as u64);
        for wd in 1..14 {
            check_stair::<2>(len, wd, &mut value);
            check_stair::<4>(len, wd, &mut value);
        }
    }
}

/// A dense supernode's own columns, factored with two 1 × 1 pivots' shared chunks read once
/// (decision record 0093), give the factor of the plain left-looking loop bit for bit: each
/// column `c` minus `Σ_k L[·, k] d_k L[c, k]` over the finished columns, each chunk of four
/// columns one pairwise sum `(c₀a₀ + c₁a₁) + (c₂a₂ + c₃a₃)` and the rest one by one (the
/// kernel's documented order, written out here), then divided by its pivot; and the factor
/// solves `K x = b`. One dense supernode of 151 columns (every remainder of the chunks and of
/// the panels), on one thread (one panel) and shared (panels of 16).
#[test]
fn a_dense_block_factored_two_columns_at_a_time_is_the_plain_factor() {
    use rand::SeedableRng;
    let dim = 151;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(93);
    // Pivots of both signs.
    let diag = |j: usize| if j.is_multiple_of(3) { -8.0 } else { 8.0 };
    let (col_ptr, row_idx, values, dense) = dense_lower(dim, &mut rng, diag);
    let mut s = SparseLdlt::with_backend(LdltBackend::Supernodal);
    s.analyse(dim, &col_ptr, &row_idx).unwrap();
    let sym = &s.faer.as_ref().expect("analysed").symbolic;
    let mut plan = BlockPlan::new(sym, dim, &col_ptr, &row_idx, &vec![false; dim]).expect("plan");
    assert_eq!(plan.sn_begin.len(), 2, "one supernode");
    assert!(plan.sn_panels[0], "factored in panels when shared");
    // The reference, column by column, on the permuted matrix (L column-major).
    let fwd = plan.perm_fwd.clone();
    let mut l = vec![0.0; dim * dim];
    let mut d = vec![0.0; dim];
    for c in 0..dim {
        let mut col: Vec<f64> = (0..dim).map(|r| dense[fwd[r]][fwd[c]]).collect();
        let a = |k: usize, r: usize| l[k * dim + r] * (l[k * dim + c] * d[k]);
        for r in c..dim {
            let n4 = c / 4 * 4;
            for k in (0..n4).step_by(4) {
                col[r] -= (a(k, r) + a(k + 1, r)) + (a(k + 2, r) + a(k + 3, r));
            }
            for k in n4..c {
                col[r] -= a(k, r);
            }
        }
        d[c] = col[c];
        let inv = d[c].recip();
        for r in c + 1..dim {
            l[c * dim + r] = col[r] * inv;
        }
    }
    for parallel in [false, true] {
        plan.factor(&values, 0.0, 0.0, parallel).expect("a factor");
        for c in 0..dim {
            assert_eq!(
                plan.d[c].to_bits(),
                d[c].to_bits(),
                "d[{c}], shared {parallel}"
            );
            for p in plan.l_col_ptr[c]..plan.l_col_ptr[c + 1] {
                let r = plan.l_row_idx[p] as usize;
                let want = if r == c { d[c] } else { l[c * dim + r] };
                assert_eq!(
                    plan.l[p].to_bits(),
                    want.to_bits(),
                    "L[{r}, {c}], shared {parallel}"
                );
            }
        }
        let res = dense_residual(&mut plan, &dense);
        assert!(res < 1e-8, "residual {res}, shared {parallel}");
    }
}

/// faer's `SupernodalThreshold::AUTO` choice, replicated on one simplicial analysis
/// (`FaerFactor::auto_supernodal`), against faer's own analysis with `AUTO`, in AMD's order and in a
/// given one, on patterns on both sides of the threshold: element blocks of 8 to 96 variables,
/// and constraint rows coupling 6 to 80 of them. The simplicial analysis in AMD's order computed
/// here is faer's own (the same permutation and structure of `L`).
#[test]
fn the_supernodal_choice_on_one_simplicial_analysis_is_faers() {
    let mut seen = [false; 2];
    for (seed, n, m, block, row_vars, density) in [
        (1, 40, 20, 8, 6, 0.7),
        (2, 120, 60, 8, 3, 0.3),
        (3, 96, 40, 48, 12, 0.9),
        (4, 192, 90, 96, 30, 1.0),
        (5, 160, 150, 32, 80, 0.8),
        (6, 300, 100, 4, 2, 0.5),
    ] {
        let shape = KktShape {
            zero_diag_every: 7,
            block,
            density,
            row_vars,
            stride: 5,
        };
        let (pat, _) = banded_kkt(seed, (n, m), &shape, &vec![1.0; n], 1e-9);
        let (cp, ri, dim) = (&pat.mat.col_ptr, &pat.mat.row_idx, n + m);
        let faers = FaerFactor::analyse(dim, cp, ri, SupernodalThreshold::AUTO, None).unwrap();
        let (fwd, flops) = ordering::amd_order_counted(cp, ri).unwrap();
        let ours = FaerFactor::analyse(
            dim,
            cp,
            ri,
            SupernodalThreshold::FORCE_SIMPLICIAL,
            Some(&fwd),
        )
        .unwrap();
        let choice = faers.is_supernodal();
        assert_eq!(
            ours.auto_supernodal(Some(flops)),
            choice,
            "AMD order, seed {seed}"
        );
        seen[usize::from(choice)] = true;
        let faer_amd =
            FaerFactor::analyse(dim, cp, ri, SupernodalThreshold::FORCE_SIMPLICIAL, None).unwrap();
        assert_eq!(
            supernodal::simplicial_structure(&ours.symbolic),
            supernodal::simplicial_structure(&faer_amd.symbolic),
            "AMD order, seed {seed}"
        );
        // A given order (the reverse of AMD's): faer counts from the columns of L.
        let rev: Vec<usize> = fwd.iter().rev().copied().collect();
        let faers =
            FaerFactor::analyse(dim, cp, ri, SupernodalThreshold::AUTO, Some(&rev)).unwrap();
        let ours = FaerFactor::analyse(
            dim,
            cp,
            ri,
            SupernodalThreshold::FORCE_SIMPLICIAL,
            Some(&rev),
        )
        .unwrap();
        assert_eq!(
            ours.auto_supernodal(None),
            faers.is_supernodal(),
            "given order, seed {seed}"
        );
        seen[usize::from(faers.is_supernodal())] = true;
    }
    assert_eq!(
        seen,
        [true, true],
        "patterns on both sides of the threshold"
    );
}

/// The pivot pairs' analysis started from another solver's AMD order
/// ([`SparseLdlt::analyse_in_amd_order`]) is the analysis that orders anew: the same pairs,
/// the same factor and solution bit for bit. That order is the one faer's own analysis with
/// its AMD ordering makes.
#[test]
fn pivot_pairs_from_a_known_amd_order_are_the_pairs_ordered_anew() {
    for (seed, n, m, shift) in [(1, 40, 24, 0.0), (3, 90, 50, -0.3), (5, 120, 100, 0.0)] {
        let (pat, _) = random_kkt(seed, n, m, shift);
        let (dim, cp, ri) = (n + m, &pat.mat.col_ptr, &pat.mat.row_idx);
        let mut amd = SparseLdlt::new();
        amd.analyse(dim, cp, ri).unwrap();
        let order = amd.amd_order().expect("an AMD analysis").to_vec();
        let faers =
            FaerFactor::analyse(dim, cp, ri, SupernodalThreshold::FORCE_SIMPLICIAL, None).unwrap();
        let faer_order = faers.symbolic.perm().map(|p| p.arrays().0.to_vec());
        assert_eq!(Some(order.clone()), faer_order, "seed {seed}");
        let pairs = || {
            SparseLdlt::with_options(LdltOptions {
                ordering: LdltOrdering::AmdPivotPairs {
                    constraint_rows_from: n,
                },
                ..LdltOptions::default()
            })
        };
        assert!(
            pairs().amd_order().is_none(),
            "only an AMD analysis has one"
        );
        let (mut anew, mut given) = (pairs(), pairs());
        anew.analyse(dim, cp, ri).unwrap();
        given
            .analyse_in_amd_order(dim, cp, ri, Some(&order))
            .unwrap();
        assert!(anew.has_pivot_pairs(), "seed {seed}: no pair formed");
        let (Kernel::Supernodal(a), Kernel::Supernodal(b)) = (&anew.kernel, &given.kernel) else {
            panic!("seed {seed}: pivot pairs need the block kernel");
        };
        assert_eq!(a.pair, b.pair, "seed {seed}");
        assert_eq!(a.perm_fwd, b.perm_fwd, "seed {seed}");
        assert_eq!(
            anew.factor(&pat.mat.values),
            given.factor(&pat.mat.values),
            "seed {seed}"
        );
        let rhs: Vec<f64> = (0..dim).map(|i| libm::sin(i as f64 * 0.37)).collect();
        let (mut x, mut y) = (rhs.clone(), rhs);
        anew.solve(&mut x).unwrap();
        given.solve(&mut y).unwrap();
        assert!(
            x.iter().zip(&y).all(|(a, b)| a.to_bits() == b.to_bits()),
            "seed {seed}"
        );
        // The given order is the one used: another order gives other pairs' order, and an
        // order of the wrong length is ignored (ordered anew).
        let reversed: Vec<usize> = order.iter().rev().copied().collect();
        let mut other = pairs();
        other
            .analyse_in_amd_order(dim, cp, ri, Some(&reversed))
            .unwrap();
        let mut short = pairs();
        short
            .analyse_in_amd_order(dim, cp, ri, Some(&order[1..]))
            .unwrap();
        let order_of = |l: &SparseLdlt| {
            let perm = l.faer.as_ref().and_then(|f| f.symbolic.perm());
            perm.map(|p| p.arrays().0.to_vec())
        };
        assert_ne!(
            order_of(&other),
            order_of(&anew),
            "seed {seed}: the given order was not used"
        );
        assert_eq!(order_of(&short), order_of(&anew), "seed {seed}");
    }
}
