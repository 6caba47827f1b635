//! The animation's script, executed: in Node.js against a minimal stand-in DOM (playback in
//! time at the chosen speed, the time scrubber, ω and phase readouts, depth order of finger
//! and ball), and in a headless Chromium when one is installed (it draws, advances, and
//! reports no script error). Each check prints a notice and passes when its program is not
//! installed.

mod common;

use bf_plot::anim::{AnimFrame, Animation, angular_velocities, write_animation_html};
use common::{rot_z, tmp};
use std::path::Path;
use std::process::Command;

/// 2 s at 1.5 rad/s about z, frames unevenly spaced (dense in the first 0.2 s, as around an
/// impact); the finger sweeps from in front of the ball (camera side, +(1,1,1)) to behind it,
/// touching it between 0.8 s and 1.2 s.
fn animation() -> Animation {
    let mut ts: Vec<f64> = (0..100).map(|k| 0.002 * k as f64).collect();
    ts.extend((0..=36).map(|k| 0.2 + 0.05 * k as f64));
    let frames = ts
        .iter()
        .map(|&t| {
            let s = 1.0 - t; // +1 in front, −1 behind
            AnimFrame {
                t,
                joints: vec![
                    [2.5, -2.0, 0.0],
                    [1.8 * s, -1.6, 0.4 + 1.2 * s],
                    [1.4 * s, 1.4 * s - 0.2, 1.4 * s],
                ],
                ball_rotation: rot_z(1.5 * t),
                contact: (0.8..=1.2).contains(&t).then_some([0.0, 0.0, 1.0]),
            }
        })
        .collect();
    Animation {
        title: "test".into(),
        ball_center: [0.0; 3],
        ball_radius: 1.0,
        frames,
    }
}

#[test]
fn angular_velocity_of_a_steady_rotation() {
    let a = animation();
    for w in angular_velocities(&a.frames) {
        assert!(w[0].abs() < 1e-9 && w[1].abs() < 1e-9, "{w:?}");
        assert!((w[2] - 1.5).abs() < 1e-9, "{w:?}");
    }
}

fn have(prog: &str) -> bool {
    Command::new(prog)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

const HARNESS: &str = r#"
const fs=require('fs');
const html=fs.readFileSync(process.argv[2],'utf8');
const src=html.split('<script>')[1].split('</script>')[0];
const els={};
function el(id){if(!els[id])els[id]={id,innerHTML:'',textContent:'',value:'',attrs:{},
  setAttribute(k,v){this.attrs[k]=v;}};return els[id];}
el('speed').value='1';
const body=el('body');
let raf=null,errors=[];
global.document={getElementById:el,body};
global.requestAnimationFrame=(cb)=>{raf=cb;};
global.window={addEventListener(k,f){}};
function out(k,v){console.log(k+'='+String(v).replace(/\n/g,' '));}
try{
  (new Function(src))();
  out('t_load',body.attrs['data-time']);
  raf(1000);raf(1500);
  out('t_half',body.attrs['data-time']);
  el('speed').value='10';raf(1600);
  out('t_fast',body.attrs['data-time']);
  const sc=el('scrub');sc.value='0.25';sc.oninput.call(sc);
  out('t_scrub',body.attrs['data-time']);
  out('omega',el('omega').textContent);
  out('phase_free',el('phase').textContent);
  sc.value='1.0';sc.oninput.call(sc);
  out('phase_contact',el('phase').textContent);
  out('scene_mid',el('scene').innerHTML);
  sc.value='0.1';sc.oninput.call(sc);
  out('scene_front',el('scene').innerHTML);
  sc.value='1.9';sc.oninput.call(sc);
  out('scene_back',el('scene').innerHTML);
  raf(1700);
  out('t_paused',body.attrs['data-time']);
  out('drawn',body.attrs['data-drawn']);
}catch(e){out('error',e.stack||e);}
"#;

fn run_node(html: &Path) -> Vec<(String, String)> {
    let dir = html.parent().unwrap();
    let h = dir.join("harness.js");
    std::fs::write(&h, HARNESS).unwrap();
    let o = Command::new("node").arg(&h).arg(html).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8(o.stdout)
        .unwrap()
        .lines()
        .filter_map(|l| l.split_once('='))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

#[test]
fn script_plays_in_time_and_draws_in_depth_order() {
    if !have("node") {
        println!("NOTICE: node not installed; the animation script was not executed");
        return;
    }
    let d = tmp("node");
    let p = write_animation_html(&animation(), d.join("a.html")).unwrap();
    let kv = run_node(&p);
    let get = |k: &str| -> &str {
        kv.iter()
            .find(|(a, _)| a == k)
            .map(|(_, v)| v.as_str())
            .unwrap_or_else(|| panic!("{k} missing: {kv:?}"))
    };
    assert!(kv.iter().all(|(k, _)| k != "error"), "{kv:?}");
    let num = |k: &str| get(k).parse::<f64>().unwrap();
    // Time-proportional playback: 0.5 s of wall time at 1× is 0.5 s of motion, although the
    // first 0.2 s hold 100 of the 137 frames; 0.1 s at 10× is 1 s more.
    assert!(num("t_load").abs() < 1e-9);
    assert!((num("t_half") - 0.5).abs() < 1e-6, "{}", get("t_half"));
    assert!((num("t_fast") - 1.5).abs() < 1e-6, "{}", get("t_fast"));
    // The scrubber sets the time in seconds and pauses.
    assert!((num("t_scrub") - 0.25).abs() < 1e-9);
    assert_eq!(num("t_paused"), 1.9, "paused after scrubbing");
    assert!(
        get("omega").contains("(0.00, 0.00, 1.50) rad/s"),
        "{}",
        get("omega")
    );
    assert_eq!(get("phase_free"), "phase: free motion");
    assert_eq!(get("phase_contact"), "phase: contact");
    // Depth order: pieces behind the ball come before the ball's disc, the others after it.
    let order = |scene: &str| {
        let ball = scene.find("class=\"ball\"").unwrap();
        let back: Vec<usize> = scene.match_indices("finger back").map(|m| m.0).collect();
        let front: Vec<usize> = scene.match_indices("finger front").map(|m| m.0).collect();
        assert!(back.iter().all(|&i| i < ball) && front.iter().all(|&i| i > ball));
        (back.len(), front.len())
    };
    let (b0, f0) = order(get("scene_front"));
    let (b1, f1) = order(get("scene_back"));
    let (bm, fm) = order(get("scene_mid"));
    assert!(f0 > b0 && b1 > f1, "front {b0}/{f0}, back {b1}/{f1}");
    assert!(bm > 0 && fm > 0);
    // The triad and the contact point are drawn.
    assert_eq!(get("scene_mid").matches("class=\"triad\"").count(), 6);
    assert!(get("scene_mid").contains("class=\"contact\""));
    assert!(!get("scene_front").contains("class=\"contact\""));
}

#[test]
fn headless_chromium_draws_and_advances() {
    let Some(browser) = ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|b| have(b))
    else {
        println!("NOTICE: no headless Chromium installed; browser check of the animation skipped");
        return;
    };
    let d = tmp("chromium");
    let p = write_animation_html(&animation(), d.join("a.html")).unwrap();
    // Headless Chromium produces animation frames within its virtual-time budget only when the
    // renderer gets scheduled; on a loaded machine a run can end before the second frame. The
    // script's timing is checked deterministically by the Node test above; here each of up to
    // eight runs must be free of script errors, and one of them must draw and advance. Three
    // runs in a row that ended after the first frame were seen once in a CI run of the whole
    // suite (and none in the reruns), and five runs half a second apart once on a machine busy
    // with other builds, so the runs are spaced by pauses that double up to 4 s (at most eight
    // runs, some 20 s of pauses) and let the load that starved the renderer pass.
    let mut advanced = None;
    for run in 0..8u32 {
        if run > 0 {
            let pause = (250u64 << run.min(5)).min(4000);
            std::thread::sleep(std::time::Duration::from_millis(pause));
        }
        let o = Command::new(browser)
            .args([
                "--headless",
                "--disable-gpu",
                "--no-sandbox",
                "--virtual-time-budget=5000",
                "--dump-dom",
            ])
            .arg(format!("file://{}", p.display()))
            .output()
            .unwrap();
        let dom = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(!dom.contains("data-error=\""), "script error: {dom}");
        // A run the browser ended before the script set its attributes (empty DOM dump) counts
        // as one that did not advance.
        let attr = |k: &str| -> Option<f64> {
            let i = dom.find(&format!("{k}=\""))?;
            let v = &dom[i + k.len() + 2..];
            v[..v.find('"')?].parse().ok()
        };
        let (drawn, time) = (attr("data-drawn"), attr("data-time"));
        if drawn.is_some_and(|d| d > 2.0) && time.is_some_and(|t| t > 0.0) {
            advanced = Some(dom);
            break;
        }
        println!(
            "headless run drew {drawn:?} frames up to t = {time:?} (status {}); retrying",
            o.status
        );
    }
    let dom = advanced.expect("did not draw and advance in eight headless runs");
    assert!(dom.contains("class=\"ball\""));
}
