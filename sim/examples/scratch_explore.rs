use bf_model::{fixtures, ImpactLaw, Mode, State, Vec3};
use bf_sim::ball_finger::{BallFinger, BallFingerOptions};
use bf_sim::{SimSettings, TorqueSeries, simulate};

fn main() {
    let model = fixtures::paper_scene().unwrap();
    let mut q = Vec3::new(0.1, 0.5, 0.5);
    let mut grad = Vec3::zeros();
    for _ in 0..100 {
        let c = model.evaluate(&State::new(q, Vec3::zeros(), Vec3::zeros())).unwrap().contact;
        grad = c.j_c.transpose() * c.n;
        if c.h.abs() < 1e-14 { break; }
        q -= grad * (c.h / grad.norm_squared());
    }
    let kin = model.evaluate(&State::new(q, Vec3::zeros(), Vec3::zeros())).unwrap();
    println!("qc {:?} grad {:?} alpha {} sat {} g {:?} pc {:?}", q, grad, kin.contact.alpha, kin.contact.sat_alpha, kin.cqd_g, kin.contact.p_c);
    let dir = grad / grad.norm();
    // tangent direction in joint space: J_c^T t with t tangent
    let n = kin.contact.n;
    let t = n.cross(&Vec3::z()).normalize();
    let jt = kin.contact.j_c.transpose() * t;
    println!("n {:?} t {:?} jt {:?}", n, t, jt);
    let x0 = State::new(q + dir * 0.05, Vec3::zeros(), Vec3::zeros()).to_array();
    let g = kin.cqd_g;
    let args: Vec<f64> = std::env::args().skip(1).map(|s| s.parse().unwrap()).collect();
    let (push, tang, pull) = (args[0], args[1], args[2]);
    let t1 = 0.5; let t2 = 1.0; let t3 = 1.5;
    let mk = |a: f64, b: f64| -> Vec<f64> { let v = g - dir * a + jt * b; vec![v[0], v[1], v[2]] };
    let ts = TorqueSeries::new(vec![0.0, t1, t2, t3, t3 + 0.01, 3.0], vec![mk(push,0.0), mk(push,0.0), mk(push, tang), mk(push,tang), mk(-pull, tang), mk(-pull, 0.0)]).unwrap();
    let sys = BallFinger::new(model, ts, BallFingerOptions { impact_law: ImpactLaw::Stick, ..Default::default() }).unwrap();
    let r = simulate(&sys, SimSettings::default(), Mode::Free, 0.0, &x0, 2.5);
    let out = match r { Ok(o) => o, Err(f) => { println!("FAIL {}", f); f.partial } };
    for e in &out.events { println!("{:.6} {} {:?} -> {:?} chained {}", e.t, e.guard, e.mode_before, e.mode_after, e.chained); }
    println!("{:?}", out.stats);
}
