//! The speculative factorization's two guarantees: a duplicate solver factors bit for bit as
//! a freshly analysed one whatever it factored before, and the [`Speculator`] hands over the
//! factor of exactly the matrix asked for and of no other.

use super::*;

/// `(inertia, solution of K x = b)` of `values` with `s`, for a fixed right-hand side.
fn factor_and_solve(s: &mut SparseLdlt, values: &[f64]) -> (Inertia, Vec<u64>) {
    let inertia = s.factor(values).expect("a factor");
    let mut x: Vec<f64> = (0..s.faer.as_ref().map_or(0, |a| a.col_ptr.len() - 1))
        .map(|i| 1.0 + (i % 7) as f64 * 0.25)
        .collect();
    s.solve(&mut x).expect("a solve");
    (inertia, x.iter().map(|v| v.to_bits()).collect())
}

/// The matrices of an inertia-correction chain on a random indefinite KKT: δ_w = 0, then
/// grown eightfold from 0.01 (as `HessianPerturbation` does), up to 41.
fn chain(pat: &KktPattern) -> Vec<Vec<f64>> {
    let mut out = vec![pat.mat.values.clone()];
    let mut w: f64 = 0.0;
    for _ in 0..6 {
        let next = if w == 0.0 { 0.01 } else { 8.0 * w };
        let mut v = Vec::new();
        let mut shifted = pat.clone();
        shifted.mat.values = out.last().expect("one matrix").clone();
        shifted.shifted_values(next - w, 0.0, &mut v);
        out.push(v);
        w = next;
    }
    out
}

#[test]
fn a_duplicate_factors_bit_for_bit_as_a_fresh_analysis() {
    for backend in [
        LdltBackend::Auto,
        LdltBackend::Simplicial,
        LdltBackend::Supernodal,
        LdltBackend::Multifrontal,
        LdltBackend::FaerSimplicial,
        LdltBackend::FaerSupernodal,
    ] {
        for (seed, n, m) in [(3, 60, 30), (8, 90, 50)] {
            let (pat, _) = random_kkt(seed, n, m, 0.0);
            let dim = n + m;
            let (cp, ri) = (&pat.mat.col_ptr, &pat.mat.row_idx);
            let mut original = SparseLdlt::with_backend(backend);
            assert!(original.duplicate().is_none(), "no copy before an analysis");
            original.analyse(dim, cp, ri).unwrap();
            let mut copy = original.duplicate().expect("a copy");
            assert_eq!(copy.options(), original.options());
            let matrices = chain(&pat);
            // The copy factors the chain backwards and the original forwards, so each
            // factor of the copy follows another matrix than the original's did.
            let forward: Vec<_> = matrices
                .iter()
                .map(|v| {
                    original
                        .factor(v)
                        .map(|_| factor_and_solve(&mut original, v))
                })
                .collect();
            for (k, v) in matrices.iter().enumerate().rev() {
                let got = copy.factor(v).map(|_| factor_and_solve(&mut copy, v));
                assert_eq!(got, forward[k], "{backend:?} seed {seed} matrix {k}");
                let mut fresh = SparseLdlt::with_backend(backend);
                fresh.analyse(dim, cp, ri).unwrap();
                let again = fresh.factor(v).map(|_| factor_and_solve(&mut fresh, v));
                assert_eq!(again, forward[k], "{backend:?} seed {seed} fresh {k}");
            }
            assert!(
                forward
                    .iter()
                    .any(|r| r.as_ref().is_ok_and(|(i, _)| i.negative == m)),
                "{backend:?} seed {seed}: some matrix of the chain has the KKT inertia"
            );
            assert!(
                forward
                    .iter()
                    .any(|r| r.as_ref().is_ok_and(|(i, _)| i.negative > m)),
                "{backend:?} seed {seed}: some matrix of the chain is rejected"
            );
        }
    }
}

#[test]
fn the_speculator_hands_over_the_factor_of_exactly_the_matrix_asked_for() {
    let (pat, _) = random_kkt(5, 120, 60, 0.0);
    let dim = pat.mat.dim;
    let matrices = chain(&pat);
    let mut solver = SparseLdlt::new();
    solver
        .analyse(dim, &pat.mat.col_ptr, &pat.mat.row_idx)
        .unwrap();
    let mut reference = SparseLdlt::new();
    reference
        .analyse(dim, &pat.mat.col_ptr, &pat.mat.row_idx)
        .unwrap();
    let mut spec = Speculator::new();
    for k in 1..matrices.len() {
        // The caller factors matrix k − 1 while the second thread factors matrix k.
        assert!(spec.start(&solver, |out| out.clone_from(&matrices[k])));
        solver.factor(&matrices[k - 1]).ok();
        // Another matrix (one bit of one entry changed) is not handed over ...
        let mut other = matrices[k].clone();
        other[0] = f64::from_bits(other[0].to_bits() ^ 1);
        assert!(spec.take(&mut solver, &other).is_none());
        // ... the one started is, with the factor a direct factorization computes.
        let (result, _) = spec.take(&mut solver, &matrices[k]).expect("the factor");
        assert_eq!(result, reference.factor(&matrices[k]));
        if result.is_ok() {
            assert_eq!(
                factor_and_solve(&mut solver, &matrices[k]),
                factor_and_solve(&mut reference, &matrices[k])
            );
        }
        // Taken once: the job is gone.
        assert!(spec.take(&mut solver, &matrices[k]).is_none());
    }
    assert!(spec.take_busy() > std::time::Duration::ZERO);
}
