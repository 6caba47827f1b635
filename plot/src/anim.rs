//! Self-contained HTML animation of the finger rolling the ball (inline SVG + inline JS, no
//! network access, no external files).
//!
//! Per frame: time t, the world positions of every DH frame origin (base o_f … fingertip p_e,
//! Sect. 2.1 / App. A), the ball orientation R (body → world, the integral of ω), and the contact
//! point p_c (eq. 3) when in contact. The ball carries three body-fixed great circles, rotated by
//! R, so its rotation is visible; the halves facing away from the camera are drawn faint.
//! Projection: the isometric view of [`crate::scene3d`] ([`ISO_EU`], [`ISO_EV`], [`ISO_D`]).
//! Playback and the scrubber run in time; the finger is drawn in depth order with the ball;
//! an axes triad and a readout of t, ω ([`angular_velocities`]) and the phase accompany it.

use crate::PlotError;
use crate::scene3d::{ISO_D, ISO_EU, ISO_EV, View};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One animation frame.
#[derive(Clone, Debug, PartialEq)]
pub struct AnimFrame {
    /// Time \[s\].
    pub t: f64,
    /// World positions of the frame origins from the finger base to the fingertip \[m\].
    pub joints: Vec<[f64; 3]>,
    /// Ball orientation: rotation matrix body → world, row-major.
    pub ball_rotation: [[f64; 3]; 3],
    /// Contact point \[m\] when the finger touches the ball.
    pub contact: Option<[f64; 3]>,
}

/// A whole animation.
#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    /// Page heading.
    pub title: String,
    /// Ball centre o_b \[m\].
    pub ball_center: [f64; 3],
    /// Ball radius r \[m\].
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

/// Ball angular velocity [rad/s] (world frame) per frame from consecutive orientations:
/// R_{k+1} R_kᵀ = exp(S(ω) Δt) for Ṙ = S(ω) R, so ω = log(R_{k+1} R_kᵀ)^∨ / Δt (forward
/// difference; the last frame repeats the one before, frames with Δt = 0 repeat their
/// predecessor).
pub fn angular_velocities(frames: &[AnimFrame]) -> Vec<[f64; 3]> {
    let n = frames.len();
    let mut out = vec![[0.0; 3]; n];
    for k in 0..n.saturating_sub(1) {
        let (a, b) = (&frames[k], &frames[k + 1]);
        let dt = b.t - a.t;
        if dt <= 0.0 {
            out[k] = if k > 0 { out[k - 1] } else { [0.0; 3] };
            continue;
        }
        let (r0, r1) = (&a.ball_rotation, &b.ball_rotation);
        let m = |i: usize, j: usize| (0..3).map(|l| r1[i][l] * r0[j][l]).sum::<f64>();
        let tr = m(0, 0) + m(1, 1) + m(2, 2);
        let th = libm::acos(((tr - 1.0) / 2.0).clamp(-1.0, 1.0));
        let f = if th < 1e-6 {
            0.5
        } else {
            th / (2.0 * libm::sin(th))
        };
        out[k] = [
            f * (m(2, 1) - m(1, 2)) / dt,
            f * (m(0, 2) - m(2, 0)) / dt,
            f * (m(1, 0) - m(0, 1)) / dt,
        ];
    }
    if n >= 2 {
        out[n - 1] = out[n - 2];
    }
    out
}

/// The HTML page (one `{t:` object per frame in the inline `FRAMES` array).
///
/// Playback is by time: the scrubber's value is the time in seconds and the animation advances
/// at the chosen speed (0.1× to 10×) whatever the frame spacing. The finger is drawn in depth
/// order with the ball: link pieces and joints behind the ball's centre plane (as seen from
/// the camera) are drawn before the ball and hidden by it, the others after. An axes triad
/// shows the world x, y, z directions; the readout gives t, ω (world frame) and the phase.
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

    let omega = angular_velocities(&a.frames);
    let mut frames = String::new();
    for (f, om) in a.frames.iter().zip(&omega) {
        let j: Vec<String> = f.joints.iter().map(vec3).collect();
        let r = f.ball_rotation;
        let c = f.contact.as_ref().map_or("null".to_string(), vec3);
        let _ = writeln!(
            frames,
            "{{t:{},j:[{}],r:[{}],c:{},w:{}}},",
            num(f.t),
            j.join(","),
            r.iter()
                .flatten()
                .map(|&v| num(v))
                .collect::<Vec<_>>()
                .join(","),
            c,
            vec3(om)
        );
    }
    let title = html_escape(&a.title);
    let n = a.frames.len();
    let (t0, t1) = (a.frames[0].t, a.frames[n - 1].t);
    let step = if t1 > t0 { (t1 - t0) / 2000.0 } else { 1.0 };
    let tstep = format!("{step:e}");
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
#scrub{{width:520px}}svg{{border:1px solid #ccc;background:#fff}}#readout span{{margin-right:18px;font-family:monospace}}</style></head>
<body><h2>{title}</h2>
<svg id="scene" data-frames="{n}" width="{w}" height="{h}" viewBox="0 0 {w} {h}"></svg>
<div id="ctl"><button id="play">Pause</button>
<input id="scrub" type="range" min="{tmin}" max="{tmax}" value="{tmin}" step="{tstep}">
<label> speed <select id="speed"><option>0.1</option><option>0.25</option><option>0.5</option><option selected>1</option><option>2</option><option>5</option><option>10</option></select></label></div>
<div id="readout"><span id="time">t = 0.000 s</span><span id="omega">ω = (0, 0, 0) rad/s</span><span id="phase">phase: free motion</span></div>
<p>Isometric view (camera along −(1,1,1)); the scrubber and playback run in time (seconds), not frames.
Black: finger links and joints (hidden by the ball where behind it); grey: ball; coloured circles:
body-fixed great circles of the ball (faint = back side); red dot: contact point; triad: world x, y, z.
ω: ball angular velocity in world axes.</p>
<script>
"use strict";
{consts}
const FRAMES=[
{frames}];
function P(p){{return [OX+S*(p[0]*EU[0]+p[1]*EU[1]+p[2]*EU[2]),OY-S*(p[0]*EV[0]+p[1]*EV[1]+p[2]*EV[2])];}}
function depth(p){{return (p[0]-C[0])*D[0]+(p[1]-C[1])*D[1]+(p[2]-C[2])*D[2];}}
const GC=[];
for(let k=0;k<3;k++){{const c=[];for(let i=0;i<=48;i++){{const a=2*Math.PI*i/48,x=Math.cos(a),y=Math.sin(a);
c.push(k===0?[x,y,0]:k===1?[x,0,y]:[0,x,y]);}}GC.push(c);}}
const GCOL=["#1f77b4","#ff7f0e","#2ca02c"];
function rot(r,p){{return [r[0]*p[0]+r[1]*p[1]+r[2]*p[2],r[3]*p[0]+r[4]*p[1]+r[5]*p[2],r[6]*p[0]+r[7]*p[1]+r[8]*p[2]];}}
function f2(v){{return v.toFixed(1);}}
function line(a,b,col,w,op,cls){{return '<line class="'+cls+'" x1="'+f2(a[0])+'" y1="'+f2(a[1])+'" x2="'+f2(b[0])+'" y2="'+f2(b[1])+'" stroke="'+col+'" stroke-width="'+w+'" stroke-linecap="round" opacity="'+op+'"/>';}}
const T0=FRAMES[0].t,T1=FRAMES[FRAMES.length-1].t;
// Largest frame index whose time is <= t (binary search).
function frameAt(t){{let lo=0,hi=FRAMES.length-1;if(t>=FRAMES[hi].t)return hi;
  while(hi-lo>1){{const m=(lo+hi)>>1;if(FRAMES[m].t<=t)lo=m;else hi=m;}}return lo;}}
// Finger pieces (8 per link) and joints split by the camera-side half space of the ball centre.
function finger(f,front){{let s="";const J=f.j;
  for(let m=0;m+1<J.length;m++){{for(let q=0;q<8;q++){{
    const a=[0,1,2].map(k=>J[m][k]+(J[m+1][k]-J[m][k])*q/8),b=[0,1,2].map(k=>J[m][k]+(J[m+1][k]-J[m][k])*(q+1)/8);
    const mid=[0,1,2].map(k=>0.5*(a[k]+b[k]));
    if((depth(mid)>=0)===front)s+=line(P(a),P(b),"#111",6,1,front?"finger front":"finger back");}}}}
  for(let m=0;m<J.length;m++){{if((depth(J[m])>=0)!==front)continue;const q=P(J[m]);
    s+='<circle class="joint" cx="'+f2(q[0])+'" cy="'+f2(q[1])+'" r="'+(m===0?8:5)+'" fill="'+(m===0?"#555":"#fff")+'" stroke="#111" stroke-width="2"/>';}}
  return s;}}
function triad(){{let s="";const o=[60,580],L=40,lab=["x","y","z"],col=["#d62728","#2ca02c","#1f77b4"];
  for(let k=0;k<3;k++){{const d=[EU[k]*L,-EV[k]*L];const e=[o[0]+d[0],o[1]+d[1]];
    s+=line(o,e,col[k],3,1,"triad");
    s+='<text class="triad" x="'+f2(o[0]+1.3*d[0]-4)+'" y="'+f2(o[1]+1.3*d[1]+5)+'" font-size="14" fill="'+col[k]+'">'+lab[k]+'</text>';}}
  return s;}}
const TRIAD=triad();
let drawn=0;
function draw(t){{
  const i=frameAt(t),f=FRAMES[i];let s="";
  const c=P(C);
  s+=finger(f,false);
  s+='<circle class="ball" cx="'+f2(c[0])+'" cy="'+f2(c[1])+'" r="'+f2(S*R)+'" fill="#f4f4f4" stroke="#444" stroke-width="2"/>';
  let front="";
  for(let k=0;k<3;k++){{const g=GC[k];for(let m=0;m<g.length-1;m++){{
    const a=rot(f.r,g[m]),b=rot(f.r,g[m+1]);
    const fr=(a[0]+b[0])*D[0]+(a[1]+b[1])*D[1]+(a[2]+b[2])*D[2]>=0;
    const pa=P([C[0]+R*a[0],C[1]+R*a[1],C[2]+R*a[2]]),pb=P([C[0]+R*b[0],C[1]+R*b[1],C[2]+R*b[2]]);
    const el=line(pa,pb,GCOL[k],fr?3:1,fr?1:0.25,"gc");if(fr)front+=el;else s+=el;}}
    const q=rot(f.r,g[0]);const pq=P([C[0]+R*q[0],C[1]+R*q[1],C[2]+R*q[2]]);
    const fq=q[0]*D[0]+q[1]*D[1]+q[2]*D[2]>=0;
    const dot='<circle class="gc" cx="'+f2(pq[0])+'" cy="'+f2(pq[1])+'" r="6" fill="'+GCOL[k]+'" opacity="'+(fq?1:0.3)+'"/>';
    if(fq)front+=dot;else s+=dot;}}
  s+=front;
  s+=finger(f,true);
  if(f.c){{const q=P(f.c);s+='<circle class="contact" cx="'+f2(q[0])+'" cy="'+f2(q[1])+'" r="7" fill="#d62728" stroke="#fff" stroke-width="2"/>';}}
  s+=TRIAD;
  document.getElementById("scene").innerHTML=s;
  const w=f.w,wn=Math.hypot(w[0],w[1],w[2]);
  document.getElementById("time").textContent="t = "+t.toFixed(3)+" s";
  document.getElementById("omega").textContent="ω = ("+w.map(v=>v.toFixed(2)).join(", ")+") rad/s, |ω| = "+wn.toFixed(2)+" rad/s";
  document.getElementById("phase").textContent="phase: "+(f.c?"contact":"free motion");
  document.getElementById("scrub").value=String(t);
  drawn++;document.body.setAttribute("data-drawn",String(drawn));document.body.setAttribute("data-time",t.toFixed(6));
}}
let playing=true,simT=T0,last=null;
function tick(ts){{
  if(playing){{
    if(last!==null){{simT+=(ts-last)/1000*parseFloat(document.getElementById("speed").value);}}
    if(simT>T1||FRAMES.length<2){{simT=T0;}}
    draw(simT);
  }}
  last=ts;requestAnimationFrame(tick);
}}
document.getElementById("play").onclick=function(){{playing=!playing;this.textContent=playing?"Pause":"Play";}};
document.getElementById("scrub").oninput=function(){{playing=false;document.getElementById("play").textContent="Play";
  simT=Math.min(T1,Math.max(T0,parseFloat(this.value)));draw(simT);}};
window.addEventListener("error",function(e){{document.body.setAttribute("data-error",String(e.message));}});
draw(T0);requestAnimationFrame(tick);
</script></body></html>
"##,
        tmin = num(t0),
        tmax = num(t1),
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
