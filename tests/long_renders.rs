//! Long renders: interruption and resume (bit for bit), checkpoints, budgets (time, noise,
//! adaptive), partial images and AOV layers.

mod common;

use common::cli::*;
use mcrt::checkpoint::read_checkpoint;
use mcrt::image::{read_exr, Image};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn cornell() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml")
}

/// `mcrt render` of the Cornell box at `size`², one thread, seed 5 unless `extra` gives one.
fn render_cmd(out: &Path, size: u32, extra: &[&str]) -> Command {
    let mut c = Command::new(BIN);
    let size = size.to_string();
    c.arg("render")
        .arg(cornell())
        .arg("-o")
        .arg(out)
        .args(["--width", &size, "--height", &size, "--threads", "1"])
        .args(extra);
    if !extra.contains(&"--seed") {
        c.args(["--seed", "5"]);
    }
    c
}

fn ok(o: &Output, what: &str) {
    assert!(
        o.status.success(),
        "{what} failed ({:?}): {}",
        o.status,
        String::from_utf8_lossy(&o.stderr)
    );
}

fn bits(img: &Image) -> Vec<[u32; 3]> {
    img.pixels
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

/// Sends SIGINT to a child process.
fn interrupt(pid: u32) {
    let s = Command::new("kill")
        .args(["-INT", &pid.to_string()])
        .status()
        .unwrap();
    assert!(s.success());
}

/// Waits for `path` to exist (up to `limit`).
fn wait_for(path: &Path, limit: Duration) -> bool {
    let t = Instant::now();
    while t.elapsed() < limit {
        if path.exists() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    false
}

/// kill -INT in the middle of a render: exit status 130, the image and a checkpoint are
/// written; `--resume` to N spp then gives the uninterrupted N-spp render bit for bit.
#[test]
fn interrupted_and_resumed_equals_uninterrupted() {
    let dir = TempDir::new("interrupt");
    let out = dir.path().join("img.exr");
    let ckpt = dir.path().join("img.checkpoint.exr");
    // Far more samples than it can render before the signal; partial images every 50 ms
    // show that the render (and the signal handler) has started.
    let child = render_cmd(&out, 24, &["--spp", "1000000", "--write-partial", "50ms"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    assert!(wait_for(&out, Duration::from_secs(60)), "no partial image");
    std::thread::sleep(Duration::from_millis(300));
    interrupt(child.id());
    let o = child.wait_with_output().unwrap();
    let err = stderr_of(&o);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("stopped: interrupted"), "{err}");
    assert!(err.contains("--resume"), "{err}");
    let c = read_checkpoint(&ckpt).expect("a checkpoint");
    let (lo, hi) = (*c.next.iter().min().unwrap(), *c.next.iter().max().unwrap());
    assert!(lo >= 1 && hi < 1000000, "samples done {lo}..{hi}");
    assert_eq!(c.meta.spp, hi);
    assert_eq!(c.meta.count, lo);
    // The image written on interruption is the checkpoint's.
    assert!(bits(&read_exr(&out).unwrap()) == bits(&c.film.image()));

    // Resume to a few more samples than the checkpoint holds, and render those at once.
    let spp = (hi + 3).to_string();
    let resumed = dir.path().join("resumed.exr");
    let o = render_cmd(
        &resumed,
        24,
        &["--spp", &spp, "--resume", ckpt.to_str().unwrap()],
    )
    .output()
    .unwrap();
    ok(&o, "resume");
    assert!(stderr_of(&o).contains(&format!("resumed from {lo} spp")));
    let whole = dir.path().join("whole.exr");
    ok(
        &render_cmd(&whole, 24, &["--spp", &spp]).output().unwrap(),
        "render",
    );
    let (a, b) = (read_exr(&resumed).unwrap(), read_exr(&whole).unwrap());
    assert!(a.pixels.iter().any(|p| p.max_element() > 0.0));
    assert!(
        bits(&a) == bits(&b),
        "interrupted at {lo}..{hi} spp and resumed to {spp}: differs from one render"
    );
}

/// A checkpoint written by --checkpoint at the end of a complete render is a sums file that
/// `merge` accepts, and resuming it to more samples equals rendering those at once.
#[test]
fn checkpoint_continues_to_more_samples() {
    let dir = TempDir::new("ckpt");
    let out = dir.path().join("a.exr");
    let ckpt = dir.path().join("state.exr");
    let o = render_cmd(
        &out,
        16,
        &["--spp", "5", "--checkpoint", ckpt.to_str().unwrap()],
    )
    .output()
    .unwrap();
    ok(&o, "render");
    let c = read_checkpoint(&ckpt).unwrap();
    assert!(c.next.iter().all(|&n| n == 5));
    let merged = dir.path().join("merged.exr");
    ok(
        &run(&[
            "merge".as_ref(),
            ckpt.as_os_str(),
            "-o".as_ref(),
            merged.as_os_str(),
        ]),
        "merge of a checkpoint",
    );
    assert!(bits(&read_exr(&merged).unwrap()) == bits(&read_exr(&out).unwrap()));
    let more = dir.path().join("more.exr");
    ok(
        &render_cmd(
            &more,
            16,
            &["--spp", "12", "--resume", ckpt.to_str().unwrap()],
        )
        .output()
        .unwrap(),
        "resume",
    );
    let once = dir.path().join("once.exr");
    ok(
        &render_cmd(&once, 16, &["--spp", "12"]).output().unwrap(),
        "render",
    );
    assert!(bits(&read_exr(&more).unwrap()) == bits(&read_exr(&once).unwrap()));
}

/// `--resume` refuses, with exit status 2 and a reason, a checkpoint of another render.
#[test]
fn resume_refuses_a_checkpoint_of_another_render() {
    let dir = TempDir::new("resume-refuse");
    let ckpt = dir.path().join("state.exr");
    let out = dir.path().join("a.exr");
    ok(
        &render_cmd(
            &out,
            16,
            &["--spp", "4", "--checkpoint", ckpt.to_str().unwrap()],
        )
        .output()
        .unwrap(),
        "render",
    );
    let c = ckpt.to_str().unwrap();
    for (size, extra, expect) in [
        (
            16,
            vec!["--seed", "6", "--spp", "8"],
            "seed 5 in the checkpoint, 6 now",
        ),
        (16, vec!["--spp", "8", "--integrator", "direct"], "settings"),
        (
            20,
            vec!["--spp", "8"],
            "image size 16 × 16 in the checkpoint, 20 × 20 now",
        ),
        (16, vec!["--spp", "2"], "already holds 4 samples per pixel"),
    ] {
        let res = dir.path().join("res.exr");
        let mut args = extra.clone();
        args.extend(["--resume", c]);
        let o = render_cmd(&res, size, &args).output().unwrap();
        let err = stderr_of(&o);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {err}");
        assert!(err.contains(expect), "{extra:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(!res.exists());
    }
    // An image is not a checkpoint; neither is a --pass sums file.
    let part = dir.path().join("part.exr");
    ok(
        &render_cmd(&part, 16, &["--spp", "4", "--pass", "1/2"])
            .output()
            .unwrap(),
        "render --pass",
    );
    for (bad, expect) in [(&out, "mcrtSums"), (&part, "not a checkpoint")] {
        let res = dir.path().join("res.exr");
        let o = render_cmd(&res, 16, &["--spp", "8", "--resume", bad.to_str().unwrap()])
            .output()
            .unwrap();
        let err = stderr_of(&o);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(expect), "{err}");
    }
}
