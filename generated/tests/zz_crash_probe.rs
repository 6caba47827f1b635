//! temporary probe (will be deleted)
#[test]
fn probe() {
    use bf_generated::iiwa7 as g;
    let q = [0.1; 7];
    let p = g::PARAM_DEFAULTS;
    let mut m = [[[0.0; 7]; 7]; 7];
    let mut c = [[0.0; 7]; 7];
    let mut v = [0.0; 7];
    let _ = (&mut m, &mut c, &mut v);
    g::cqd_g(&q, &q, &p, &mut v);
    println!("{m:?} {c:?} {v:?}");
}
