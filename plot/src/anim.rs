//! Self-contained HTML animation of the finger rolling the ball (inline SVG + inline JS, no
//! network access, no external files).
//!
//! Per frame: time t, the world positions of every DH frame origin (base o_f … fingertip p_e,
//! Sect. 2.1 / App. A), the ball orientation R (body → world, the integral of ω), and the contact
//! point p_c (eq. 3) when in contact. The ball carries three body-fixed great circles, rotated by
//! R, so its rotation is visible; the halves facing away from the camera are drawn faint.
//! Projection: the isometric view of [`crate::scene3d`] ([`ISO_EU`], [`ISO_EV`], [`ISO_D`]).

use crate::PlotError;
use crate::scene3d::{ISO_D, ISO_EU, ISO_EV, View};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One animation frame.
#[derive(Clone, Debug, PartialEq)]
pub struct AnimFrame {
    /// Time [s].
    pub t: f64,
    /// World positions of the frame origins from the finger base to the fingertip [m].
    pub joints: Vec<[f64; 3]>,
    /// Ball orientation: rotation matrix body → world, row-major.
    pub ball_rotation: [[f64; 3]; 3],
    /// Contact point [m] when the finger touches the ball.
    pub contact: Option<[f64; 3]>,
}

/// A whole animation.
#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    /// Page heading.
    pub title: String,
    /// Ball centre o_b [m].
    pub ball_center: [f64; 3],
    /// Ball radius r [m].
    pub ball_radius: f64,
    /// Frames in increasing time.
    pub frames: Vec<AnimFrame>,
}

fn bad(what: &str, detail: String) -> PlotError {
    PlotError::InvalidInput {
        figure: "animation".into(),
        what: what.into(),
        detail,
    }
}

fn validate(a: &Animation) -> Result<(), PlotError> {
    if a.frames.is_empty() {
        return Err(PlotError::NoSeries("animation (no frames)".into()));
    }
    if !(a.ball_radius.is_finite() && a.ball_radius > 0.0)
        || a.ball_center.iter().any(|v| !v.is_finite())
    {
        return Err(bad(
            "ball",
            format!("centre {:?}, radius {}", a.ball_center, a.ball_radius),
        ));
    }
    let nj = a.frames[0].joints.len();
    let mut prev_t = f64::NEG_INFINITY;
    for (i, f) in a.frames.iter().enumerate() {
        if !f.t.is_finite() || f.t < prev_t {
            return Err(bad(
                "frame time",
                format!("frame {i}: t = {} after {prev_t}", f.t),
            ));
        }
        prev_t = f.t;
        if f.joints.len() != nj || nj < 2 {
            return Err(PlotError::Shape {
                what: format!("frame {i} joints"),
                detail: format!("{} points, frame 0 has {nj} (need ≥ 2)", f.joints.len()),
            });
        }
        let finite = |p: &[f64; 3]| p.iter().all(|v| v.is_finite());
        if !f.joints.iter().all(finite) || f.contact.as_ref().is_some_and(|c| !finite(c)) {
            return Err(bad(
                "frame data",
                format!("frame {i} has a NaN/inf position"),
            ));
        }
        // RᵀR = I (within 1e-3): a non-rotation would silently distort the marker pattern.
        let r = &f.ball_rotation;
        for p in 0..3 {
            for q in 0..3 {
                let m: f64 = (0..3).map(|k| r[k][p] * r[k][q]).sum();
                let e = if p == q { 1.0 } else { 0.0 };
                let ok = (m - e).abs() <= 1e-3; // false for NaN too
                if !ok {
                    return Err(bad(
                        "ball rotation",
                        format!("frame {i}: not orthonormal (RᵀR[{p}][{q}] = {m})"),
                    ));
                }
            }
        }
    }
    Ok(())
}

fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn num(v: f64) -> String {
    let s = format!("{v:.5}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" || s.is_empty() {
        "0".into()
    } else {
        s.into()
    }
}

fn vec3(p: &[f64; 3]) -> String {
    format!("[{},{},{}]", num(p[0]), num(p[1]), num(p[2]))
}

/// The HTML page (one `{t:` object per frame in the inline `FRAMES` array).
pub fn animation_html(a: &Animation) -> Result<String, PlotError> {
    validate(a)?;
    // Fit the isometric projection of everything (ball outline included) into the canvas.
    let (w, h) = (800.0, 640.0);
    let (cu, cv) = View::Iso.project(a.ball_center);
    let (mut u0, mut u1, mut v0, mut v1) = (
        cu - a.ball_radius,
        cu + a.ball_radius,
        cv - a.ball_radius,
        cv + a.ball_radius,
    );
    for f in &a.frames {
        for p in f.joints.iter().chain(f.contact.iter()) {
            let (u, v) = View::Iso.project(*p);
            (u0, u1, v0, v1) = (u0.min(u), u1.max(u), v0.min(v), v1.max(v));
        }
    }
    let pad = 30.0;
    let s = ((w - 2.0 * pad) / (u1 - u0)).min((h - 2.0 * pad) / (v1 - v0));
    let ox = pad + 0.5 * (w - 2.0 * pad - s * (u1 - u0)) - s * u0;
    let oy = h - pad - 0.5 * (h - 2.0 * pad - s * (v1 - v0)) + s * v0;

    let mut frames = String::new();
    for f in &a.frames {
        let j: Vec<String> = f.joints.iter().map(vec3).collect();
        let r = f.ball_rotation;
        let c = f.contact.as_ref().map_or("null".to_string(), vec3);
        let _ = writeln!(
            frames,
            "{{t:{},j:[{}],r:[{}],c:{}}},",
            num(f.t),
            j.join(","),
            r.iter()
                .flatten()
                .map(|&v| num(v))
                .collect::<Vec<_>>()
                .join(","),
            c
        );
    }
    let title = html_escape(&a.title);
    let n = a.frames.len();
    let consts = format!(
        "const EU={},EV={},D={},S={},OX={},OY={},C={},R={};",
        vec3(&ISO_EU),
        vec3(&ISO_EV),
        vec3(&ISO_D),
        num(s),
        num(ox),
        num(oy),
        vec3(&a.ball_center),
        num(a.ball_radius)
    );
    Ok(format!(
        r##"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{title}</title>
<style>body{{font-family:sans-serif;margin:16px}}#ctl{{margin:8px 0}}#ctl *{{vertical-align:middle}}
#scrub{{width:520px}}svg{{border:1px solid #ccc;background:#fff}}</style></head>
<body><h2>{title}</h2>
<svg id="scene" data-frames="{n}" width="{w}" height="{h}" viewBox="0 0 {w} {h}"></svg>
<div id="ctl"><button id="play">Pause</button>
<input id="scrub" type="range" min="0" max="{nmax}" value="0" step="1">
<span id="time">t = 0.000 s</span>
<label> speed <select id="speed"><option>0.25</option><option>0.5</option><option selected>1</option><option>2</option></select></label></div>
<p>Isometric view (camera along −(1,1,1)). Black: finger links and joints; grey: ball; coloured circles:
body-fixed great circles of the ball (faint = back side); red dot: contact point.</p>
<script>
"use strict";
{consts}
const FRAMES=[
{frames}];
function P(p){{return [OX+S*(p[0]*EU[0]+p[1]*EU[1]+p[2]*EU[2]),OY-S*(p[0]*EV[0]+p[1]*EV[1]+p[2]*EV[2])];}}
const GC=[];
for(let k=0;k<3;k++){{const c=[];for(let i=0;i<=48;i++){{const a=2*Math.PI*i/48,x=Math.cos(a),y=Math.sin(a);
c.push(k===0?[x,y,0]:k===1?[x,0,y]:[0,x,y]);}}GC.push(c);}}
const GCOL=["#1f77b4","#ff7f0e","#2ca02c"];
function rot(r,p){{return [r[0]*p[0]+r[1]*p[1]+r[2]*p[2],r[3]*p[0]+r[4]*p[1]+r[5]*p[2],r[6]*p[0]+r[7]*p[1]+r[8]*p[2]];}}
function f2(v){{return v.toFixed(1);}}
function draw(i){{
  const f=FRAMES[i];let s="";
  const c=P(C);
  s+='<circle cx="'+f2(c[0])+'" cy="'+f2(c[1])+'" r="'+f2(S*R)+'" fill="#f4f4f4" stroke="#444" stroke-width="2"/>';
  for(let k=0;k<3;k++){{const g=GC[k];for(let m=0;m<g.length-1;m++){{
    const a=rot(f.r,g[m]),b=rot(f.r,g[m+1]);
    const front=(a[0]+b[0])*D[0]+(a[1]+b[1])*D[1]+(a[2]+b[2])*D[2]>=0;
    const pa=P([C[0]+R*a[0],C[1]+R*a[1],C[2]+R*a[2]]),pb=P([C[0]+R*b[0],C[1]+R*b[1],C[2]+R*b[2]]);
    s+='<line x1="'+f2(pa[0])+'" y1="'+f2(pa[1])+'" x2="'+f2(pb[0])+'" y2="'+f2(pb[1])+'" stroke="'+GCOL[k]+'" stroke-width="'+(front?3:1)+'" opacity="'+(front?1:0.25)+'"/>';}}
    const q=rot(f.r,g[0]);const pq=P([C[0]+R*q[0],C[1]+R*q[1],C[2]+R*q[2]]);
    const fr=q[0]*D[0]+q[1]*D[1]+q[2]*D[2]>=0;
    s+='<circle cx="'+f2(pq[0])+'" cy="'+f2(pq[1])+'" r="6" fill="'+GCOL[k]+'" opacity="'+(fr?1:0.3)+'"/>';}}
  let pts="";for(const p of f.j){{const q=P(p);pts+=f2(q[0])+","+f2(q[1])+" ";}}
  s+='<polyline points="'+pts+'" fill="none" stroke="#111" stroke-width="6" stroke-linejoin="round" stroke-linecap="round"/>';
  for(let m=0;m<f.j.length;m++){{const q=P(f.j[m]);s+='<circle cx="'+f2(q[0])+'" cy="'+f2(q[1])+'" r="'+(m===0?8:5)+'" fill="'+(m===0?"#555":"#fff")+'" stroke="#111" stroke-width="2"/>';}}
  if(f.c){{const q=P(f.c);s+='<circle cx="'+f2(q[0])+'" cy="'+f2(q[1])+'" r="7" fill="#d62728" stroke="#fff" stroke-width="2"/>';}}
  document.getElementById("scene").innerHTML=s;
  document.getElementById("time").textContent="t = "+f.t.toFixed(3)+" s"+(f.c?"  (contact)":"");
  document.getElementById("scrub").value=i;
}}
let idx=0,playing=true,simT=FRAMES[0].t,last=null;
const T0=FRAMES[0].t,T1=FRAMES[FRAMES.length-1].t;
function tick(ts){{
  if(playing){{
    if(last!==null){{simT+=(ts-last)/1000*parseFloat(document.getElementById("speed").value);}}
    if(simT>T1||FRAMES.length<2){{simT=T0;idx=0;}}
    while(idx<FRAMES.length-1&&FRAMES[idx+1].t<=simT)idx++;
    draw(idx);
  }}
  last=ts;requestAnimationFrame(tick);
}}
document.getElementById("play").onclick=function(){{playing=!playing;this.textContent=playing?"Pause":"Play";}};
document.getElementById("scrub").oninput=function(){{playing=false;document.getElementById("play").textContent="Play";
  idx=parseInt(this.value,10);simT=FRAMES[idx].t;draw(idx);}};
draw(0);requestAnimationFrame(tick);
</script></body></html>
"##,
        nmax = n - 1
    ))
}

/// Writes [`animation_html`] to `path` atomically and returns the path.
pub fn write_animation_html(a: &Animation, path: impl AsRef<Path>) -> Result<PathBuf, PlotError> {
    let html = animation_html(a)?;
    let path = path.as_ref().to_path_buf();
    crate::figure::write_atomic(&path, html.as_bytes())?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn number_format_is_compact() {
        assert_eq!(num(1.0), "1");
        assert_eq!(num(-0.0000001), "0");
        assert_eq!(num(0.25), "0.25");
        assert_eq!(num(-2.5), "-2.5");
    }

    #[test]
    fn title_is_escaped() {
        assert_eq!(html_escape("<a&b>"), "&lt;a&amp;b&gt;");
    }
}
