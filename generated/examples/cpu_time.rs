//! Per-call CPU time (user + system, from /proc/self/stat) of the paper kernels: a
//! load-independent complement to the criterion benches on a shared machine, where wall-clock
//! time includes preemption. Run: `cargo run --release -p bf-generated --example cpu_time`.

use std::hint::black_box;

fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the command name `(...)`: utime is field 14, stime 15 (1-based).
    let rest = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let tick = |i: usize| f.get(i).and_then(|s| s.parse::<f64>().ok()).unwrap_or(0.0);
    // f[0] is field 3 (state), so utime = f[11], stime = f[12]; clock ticks are 100 Hz.
    (tick(11) + tick(12)) / 100.0
}

fn time(name: &str, iters: u64, mut f: impl FnMut()) {
    let t0 = cpu_seconds();
    let w0 = std::time::Instant::now();
    for _ in 0..iters {
        f();
    }
    let cpu = cpu_seconds() - t0;
    let wall = w0.elapsed().as_secs_f64();
    println!(
        "{name:<28} cpu {:7.1} ns/call   wall {:7.1} ns/call",
        cpu / iters as f64 * 1e9,
        wall / iters as f64 * 1e9
    );
}

fn main() {
    use bf_generated::paper as s;
    let n = 20_000_000;
    let q = [0.3, -0.7, 1.1];
    let qd = [0.4, 0.2, -0.9];
    let p = s::PARAM_DEFAULTS;
    let mut m = [[0.0; 3]; 3];
    let mut v = [0.0; 3];
    let mut ct = s::Contact::default();
    time("paper/mass_cqd_g", n, || {
        s::mass_cqd_g(black_box(&q), black_box(&qd), black_box(&p), &mut m, &mut v);
        black_box((&m, &v));
    });
    time("paper/mass_matrix", n, || {
        s::mass_matrix(black_box(&q), black_box(&p), &mut m);
        black_box(&m);
    });
    time("paper/cqd_g_rnea", n, || {
        s::cqd_g_rnea(black_box(&q), black_box(&qd), black_box(&p), &mut v);
        black_box(&v);
    });
    time("paper/contact", n / 2, || {
        s::contact(
            black_box(&q),
            black_box(&qd),
            black_box(&[0.0, 0.0, 2.2]),
            black_box(&p),
            &mut ct,
        );
        black_box(&ct);
    });
    time("3 x f64::sin_cos", n, || {
        let a = libm::sincos(black_box(q[0]));
        let b = libm::sincos(black_box(q[1]));
        let c = libm::sincos(black_box(q[2]));
        black_box((a, b, c));
    });
}
