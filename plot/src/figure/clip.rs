//! Line geometry before drawing: Liang–Barsky clipping to the axes rectangle (the splitting of
//! thick bitmap strokes at sharp turns is the PNG canvas's, `canvas::split_sharp_turns`).

/// Liang–Barsky clipping of the segment a→b to the closed rectangle `xr × yr`: the parameter
/// interval `(t0, t1)` ⊆ [0, 1] of the part inside (points a + t (b − a)), or `None` if the
/// segment misses the rectangle. A degenerate segment (a = b) is kept whole iff a is inside.
pub(super) fn clip_segment(
    a: (f64, f64),
    b: (f64, f64),
    xr: (f64, f64),
    yr: (f64, f64),
) -> Option<(f64, f64)> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    // Each pair (p, q): the segment is inside this edge's half-plane where t p <= q.
    for (p, q) in [
        (-dx, a.0 - xr.0),
        (dx, xr.1 - a.0),
        (-dy, a.1 - yr.0),
        (dy, yr.1 - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
        if t0 > t1 {
            return None;
        }
    }
    Some((t0, t1))
}

/// Clips a polyline to the rectangle `xr × yr`: the maximal runs of it inside, in order. A
/// single point is kept iff it is inside. Original vertices are kept exactly; cut points are
/// interpolated on the rectangle's edges.
pub(super) fn clip_polyline(
    pts: &[(f64, f64)],
    xr: (f64, f64),
    yr: (f64, f64),
) -> Vec<Vec<(f64, f64)>> {
    if let [p] = pts {
        return clip_segment(*p, *p, xr, yr)
            .map(|_| vec![vec![*p]])
            .unwrap_or_default();
    }
    let lerp =
        |a: (f64, f64), b: (f64, f64), t: f64| (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
    let mut out = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    for w in pts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let Some((t0, t1)) = clip_segment(a, b, xr, yr) else {
            if !cur.is_empty() {
                out.push(std::mem::take(&mut cur));
            }
            continue;
        };
        // A run continues only through a vertex that is itself inside (t0 = 0 after a t1 = 1).
        if t0 > 0.0 || cur.is_empty() {
            if !cur.is_empty() {
                out.push(std::mem::take(&mut cur));
            }
            cur.push(if t0 > 0.0 { lerp(a, b, t0) } else { a });
        }
        cur.push(if t1 < 1.0 { lerp(a, b, t1) } else { b });
        if t1 < 1.0 {
            out.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}
