//! Many machines: `mcrt render --pass K/N` in separate processes, merged by `mcrt merge`, gives
//! the single render's image bit for bit; merge refuses parts that do not belong together or
//! do not cover every pass once; `mcrt compare` prints the metrics of known images and writes
//! the difference image.

mod common;

use common::cli::*;
use mcrt::image::{read_exr, write_image, Image, WriteOptions};
use mcrt::parts::{self, Pass};
use mcrt::render::render;
use mcrt::scene::desc::FileSettings;
use mcrt::scene::Scene;
use mcrt::Color;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn cornell() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml")
}

const SIZE: &str = "32";

/// `mcrt render` of the Cornell box at 32×32 with `spp` and `extra` flags (seed 5 unless
/// they give one), as a command.
fn render_cmd(out: &Path, spp: u32, extra: &[&str]) -> Command {
    let mut c = Command::new(BIN);
    c.arg("render")
        .arg(cornell())
        .arg("-o")
        .arg(out)
        .args(["--width", SIZE, "--height", SIZE, "-q"])
        .args(["--spp", &spp.to_string(), "--threads", "1"])
        .args(extra);
    if !extra.contains(&"--seed") {
        c.args(["--seed", "5"]);
    }
    c
}

fn ok(o: &Output, what: &str) {
    assert!(
        o.status.success(),
        "{what} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Renders passes 1/n … n/n as n concurrent processes; returns the parts' paths.
fn render_parts(dir: &TempDir, spp: u32, n: u32, extra: &[&str]) -> Vec<PathBuf> {
    let paths: Vec<PathBuf> = (1..=n)
        .map(|k| dir.path().join(format!("part-{k}-of-{n}.exr")))
        .collect();
    let children: Vec<_> = paths
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let pass = format!("{}/{n}", i + 1);
            let mut args = vec!["--pass", pass.as_str()];
            args.extend_from_slice(extra);
            render_cmd(p, spp, &args).spawn().unwrap()
        })
        .collect();
    for c in children {
        ok(&c.wait_with_output().unwrap(), "render --pass");
    }
    paths
}

fn merge(parts: &[PathBuf], out: &Path, extra: &[&str]) -> Output {
    Command::new(BIN)
        .arg("merge")
        .args(parts)
        .arg("-o")
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

fn bits(img: &Image) -> Vec<[u32; 3]> {
    img.pixels
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

/// The merge of `n` parts (given in reverse order) equals the single render, bit for bit.
fn check_merge_equals_single(tag: &str, spp: u32, n: u32) {
    let dir = TempDir::new(tag);
    let single = dir.path().join("single.exr");
    ok(&render_cmd(&single, spp, &[]).output().unwrap(), "render");
    let mut parts = render_parts(&dir, spp, n, &[]);
    parts.reverse();
    let merged = dir.path().join("merged.exr");
    let sums = dir.path().join("sums.exr");
    ok(
        &merge(&parts, &merged, &["--keep-sums", sums.to_str().unwrap()]),
        "merge",
    );
    let (a, b) = (read_exr(&single).unwrap(), read_exr(&merged).unwrap());
    assert_eq!((a.width, a.height), (32, 32));
    assert!(
        a.pixels.iter().any(|p| p.max_element() > 0.0),
        "the box is lit"
    );
    assert!(
        bits(&a) == bits(&b),
        "{tag}: merge of {n} passes at {spp} spp differs from the single render"
    );
    // The kept sums are pass 1/1 of the same render: the single render's own sums file.
    let whole = dir.path().join("whole.exr");
    ok(
        &render_cmd(&whole, spp, &["--pass", "1/1"])
            .output()
            .unwrap(),
        "render --pass 1/1",
    );
    let (k, w) = (
        parts::read_part(&sums).unwrap(),
        parts::read_part(&whole).unwrap(),
    );
    assert_eq!(k.meta, w.meta);
    assert_eq!(
        k.film, w.film,
        "{tag}: merged sums differ from one render's"
    );
    assert!(k.film.count.iter().all(|&c| c == spp));
    // The sums file merges on its own.
    let again = dir.path().join("again.exr");
    ok(&merge(&[sums], &again, &[]), "merge of the kept sums");
    assert!(bits(&read_exr(&again).unwrap()) == bits(&a));
}

#[test]
fn four_processes_merge_to_the_single_render() {
    check_merge_equals_single("even", 16, 4);
}

#[test]
fn uneven_splits_merge_to_the_single_render() {
    // 10 = 2 + 3 + 2 + 3 and 7 = 2 + 2 + 3.
    check_merge_equals_single("uneven-4", 10, 4);
    check_merge_equals_single("uneven-3", 7, 3);
}

#[test]
fn shares_cover_the_samples_once() {
    for spp in [1, 2, 7, 10, 16, 1000] {
        for n in 1..=12 {
            let mut next = 0;
            for k in 1..=n {
                let (first, count) = Pass { k, n }.share(spp);
                assert_eq!(first, next, "{k}/{n} of {spp}");
                assert!(count == spp / n || count == spp / n + 1);
                next = first + count;
            }
            assert_eq!(next, spp);
        }
    }
    assert_eq!(Pass { k: 2, n: 4 }.share(10), (2, 3));
    for bad in ["0/4", "5/4", "1", "a/b", "1/0", "-1/4", ""] {
        assert!(bad.parse::<Pass>().is_err(), "{bad:?}");
    }
    assert_eq!("3/8".parse::<Pass>(), Ok(Pass { k: 3, n: 8 }));
}

/// Through the library, including the sums files: the merged film of N passes is the film of
/// one render, every integer sum and count equal, for N from 1 to more passes than samples.
#[test]
fn merged_parts_equal_one_render_bit_for_bit() {
    let path = cornell();
    let scene = Scene::build(mcrt::load_scene(&path).unwrap());
    let over = FileSettings {
        width: Some(24),
        height: Some(20),
        spp: Some(6),
        seed: Some(11),
        ..Default::default()
    };
    let s = mcrt::resolve_settings(&scene.desc_settings, &over, Some(2)).unwrap();
    let (once, _) = render(&scene, &s, &|_| {}).unwrap();
    assert!(once.sum.iter().flatten().any(|&v| v > 0));
    let dir = TempDir::new("lib-merge");
    for n in [1, 2, 3, 4, 5, 8] {
        let mut list = Vec::new();
        for k in (1..=n).rev() {
            let pass = Pass { k, n };
            let (film, _) = parts::render_pass(&scene, &s, pass, &|_| {}).unwrap();
            let meta = parts::PartMeta::new(&path, b"scene", "", &s, pass);
            let p = dir.path().join(format!("{k}-{n}.exr"));
            parts::write_part(&p, &parts::Part { meta, film }).unwrap();
            list.push((p.clone(), parts::read_part(&p).unwrap()));
        }
        let merged = parts::merge(&list).unwrap();
        assert_eq!(merged.meta.pass, Pass { k: 1, n: 1 });
        assert!(merged.film == once, "{n} passes: the merged film differs");
    }
}

/// `mcrt merge` exits with status 2, names the problem and writes nothing.
fn refused(dir: &TempDir, parts: &[PathBuf], expect: &[&str]) {
    let out = dir.path().join("refused.png");
    let o = merge(parts, &out, &[]);
    let err = stderr_of(&o);
    assert_eq!(o.status.code(), Some(2), "stderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for e in expect {
        assert!(err.contains(e), "stderr should contain {e:?}: {err}");
    }
    assert!(!out.exists());
}

#[test]
fn merge_refuses_parts_that_do_not_fit() {
    let dir = TempDir::new("refuse");
    let p = render_parts(&dir, 4, 2, &[]);
    let sub = TempDir::new("refuse-other");
    let other_seed = sub.path().join("seed.exr");
    ok(
        &render_cmd(&other_seed, 4, &["--pass", "2/2", "--seed", "6"])
            .output()
            .unwrap(),
        "render",
    );
    let other_spp = sub.path().join("spp.exr");
    ok(
        &render_cmd(&other_spp, 6, &["--pass", "2/2"])
            .output()
            .unwrap(),
        "render",
    );
    let other_n = sub.path().join("n.exr");
    ok(
        &render_cmd(&other_n, 4, &["--pass", "2/3"])
            .output()
            .unwrap(),
        "render",
    );
    let other_int = sub.path().join("int.exr");
    ok(
        &render_cmd(&other_int, 4, &["--pass", "2/2", "--integrator", "direct"])
            .output()
            .unwrap(),
        "render",
    );
    let image = sub.path().join("image.exr");
    ok(&render_cmd(&image, 4, &[]).output().unwrap(), "render");

    refused(&dir, &p[..1], &["missing pass 2/2"]);
    refused(
        &dir,
        &[p[0].clone(), p[0].clone()],
        &["pass 1/2 is given twice"],
    );
    refused(
        &dir,
        &[p[0].clone(), p[1].clone(), p[1].clone()],
        &["given twice"],
    );
    refused(&dir, &[p[0].clone(), other_seed], &["seed 5 versus 6"]);
    refused(&dir, &[p[0].clone(), other_spp], &["spp 4 versus 6"]);
    refused(
        &dir,
        &[p[0].clone(), other_n],
        &["number of passes 2 versus 3"],
    );
    refused(&dir, &[p[0].clone(), other_int], &["settings"]);
    refused(
        &dir,
        &[p[0].clone(), image.clone()],
        &["image.exr", "mcrtSums"],
    );
    refused(
        &dir,
        &[p[0].clone(), dir.path().join("nonexistent.exr")],
        &["nonexistent.exr"],
    );
    // And the good pair merges.
    ok(&merge(&p, &dir.path().join("good.png"), &[]), "merge");
}

#[test]
fn pass_needs_a_valid_share_and_an_exr() {
    let dir = TempDir::new("pass-flag");
    for (pass, out, expect) in [
        ("0/4", "a.exr", "K/N"),
        ("5/4", "a.exr", "K/N"),
        ("x", "a.exr", "K/N"),
        ("1/4", "a.png", "must be .exr"),
    ] {
        let out = dir.path().join(out);
        let o = render_cmd(&out, 4, &["--pass", pass]).output().unwrap();
        let err = stderr_of(&o);
        assert_eq!(o.status.code(), Some(2), "--pass {pass}: {err}");
        assert!(err.contains(expect), "--pass {pass}: {err}");
        assert!(!out.exists());
    }
}

fn constant(w: u32, h: u32, c: Color) -> Image {
    Image {
        width: w,
        height: h,
        pixels: vec![c; (w * h) as usize],
    }
}

fn compare(args: &[&OsStr]) -> Output {
    let mut all: Vec<&OsStr> = vec!["compare".as_ref()];
    all.extend_from_slice(args);
    run(&all)
}

/// The value printed after `name` on stdout.
fn metric(out: &str, name: &str) -> f64 {
    let line = out
        .lines()
        .find(|l| l.split_whitespace().next() == Some(name))
        .unwrap_or_else(|| panic!("no {name} in {out:?}"));
    let v = line.split_whitespace().nth(1).unwrap();
    v.parse().unwrap_or_else(|_| panic!("bad {name}: {v:?}"))
}

#[test]
fn compare_known_images() {
    let dir = TempDir::new("compare");
    let a = dir.path().join("a.exr");
    let b = dir.path().join("b.exr");
    let small = dir.path().join("small.exr");
    let opts = WriteOptions::default();
    // A = 0.75 everywhere, B = 0.5: every difference is 0.25.
    write_image(&a, &constant(8, 6, Color::splat(0.75)), &opts).unwrap();
    write_image(&b, &constant(8, 6, Color::splat(0.5)), &opts).unwrap();
    write_image(&small, &constant(6, 8, Color::splat(0.5)), &opts).unwrap();
    let diff = dir.path().join("diff.exr");
    let o = compare(&[
        a.as_os_str(),
        b.as_os_str(),
        "--diff".as_ref(),
        diff.as_os_str(),
        "--diff-range".as_ref(),
        "0.5".as_ref(),
    ]);
    ok(&o, "compare");
    let out = String::from_utf8_lossy(&o.stdout);
    assert!((metric(&out, "RMSE") - 0.25).abs() < 1e-12, "{out}");
    assert!(
        (metric(&out, "relMSE") - 0.0625 / (0.25 + 0.01)).abs() < 1e-12,
        "{out}"
    );
    // 10·log10(1 / 0.0625) = 12.04 dB.
    assert!(
        (metric(&out, "PSNR") - 12.041199826559248).abs() < 1e-9,
        "{out}"
    );
    // Half the range, A brighter: halfway from white to red.
    let d = read_exr(&diff).unwrap();
    assert_eq!((d.width, d.height), (8, 6));
    assert!(d.pixels.iter().all(|&p| p == Color::new(1.0, 0.5, 0.5)));
    // Reversed, with the default range (the largest difference): pure blue, as a PNG.
    let png = dir.path().join("diff.png");
    let o = compare(&[
        b.as_os_str(),
        a.as_os_str(),
        "--diff".as_ref(),
        png.as_os_str(),
    ]);
    ok(&o, "compare");
    let out = String::from_utf8_lossy(&o.stdout);
    assert!((metric(&out, "relMSE") - 0.0625 / (0.5625 + 0.01)).abs() < 1e-12);
    let dec = png::Decoder::new(std::fs::File::open(&png).unwrap());
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (8, 6));
    assert!(buf[..info.buffer_size()]
        .chunks(3)
        .all(|p| p == [0, 0, 255]));
    // Equal images: zero error, infinite PSNR.
    let o = compare(&[a.as_os_str(), a.as_os_str()]);
    ok(&o, "compare");
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(metric(&out, "RMSE"), 0.0);
    assert_eq!(metric(&out, "PSNR"), f64::INFINITY);
    // Different sizes: refused.
    let o = compare(&[a.as_os_str(), small.as_os_str()]);
    let err = stderr_of(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("differ in size"), "{err}");
    assert!(o.stdout.is_empty());
}

/// Photon mapping renders through the same integrator seam as the path tracer: its passes
/// merge to its single render bit for bit (every process builds the same maps from the
/// seed), and a render interrupted by its time budget resumes to the same bits.
#[test]
fn photon_mapping_takes_passes_and_resumes() {
    let dir = TempDir::new("photon-passes");
    let flags = [
        "--integrator",
        "photon",
        "--photons",
        "3000",
        "--caustic-photons",
        "3000",
        "--final-gather",
        "2",
    ];
    let single = dir.path().join("single.exr");
    ok(&render_cmd(&single, 6, &flags).output().unwrap(), "render");
    let parts: Vec<PathBuf> = (1..=3)
        .map(|k| {
            let p = dir.path().join(format!("p{k}.exr"));
            let pass = format!("{k}/3");
            let mut args = flags.to_vec();
            args.extend(["--pass", pass.as_str()]);
            ok(&render_cmd(&p, 6, &args).output().unwrap(), "photon pass");
            p
        })
        .collect();
    let merged = dir.path().join("merged.exr");
    ok(&merge(&parts, &merged, &[]), "merge");
    let a = read_exr(&single).unwrap();
    assert!(a.pixels.iter().any(|p| p.max_element() > 0.0), "lit");
    assert!(
        bits(&a) == bits(&read_exr(&merged).unwrap()),
        "photon passes merged differ from the single render"
    );
    // Half the samples with a checkpoint, then resumed to all of them.
    let half = dir.path().join("half.exr");
    let ck = dir.path().join("half.checkpoint.exr");
    let mut args = flags.to_vec();
    args.extend(["--checkpoint", ck.to_str().unwrap()]);
    ok(&render_cmd(&half, 3, &args).output().unwrap(), "first half");
    let resumed = dir.path().join("resumed.exr");
    let mut args = flags.to_vec();
    args.extend(["--resume", ck.to_str().unwrap()]);
    ok(&render_cmd(&resumed, 6, &args).output().unwrap(), "resume");
    assert!(
        bits(&a) == bits(&read_exr(&resumed).unwrap()),
        "a resumed photon render differs from the single render"
    );
}

/// The backend is a render setting: forcing one path at a time gives the default's bits,
/// and a backend the CPU or the scene cannot run is refused before rendering, exit 2.
#[test]
fn backend_is_a_render_setting() {
    let dir = TempDir::new("backend");
    let auto = dir.path().join("auto.exr");
    ok(&render_cmd(&auto, 4, &[]).output().unwrap(), "auto");
    let scalar = dir.path().join("scalar.exr");
    ok(
        &render_cmd(&scalar, 4, &["--backend", "scalar"])
            .output()
            .unwrap(),
        "scalar",
    );
    assert!(bits(&read_exr(&auto).unwrap()) == bits(&read_exr(&scalar).unwrap()));
    let stream = dir.path().join("stream.exr");
    ok(
        &render_cmd(&stream, 4, &["--backend", "stream"])
            .output()
            .unwrap(),
        "stream",
    );
    assert!(bits(&read_exr(&stream).unwrap()) == bits(&read_exr(&scalar).unwrap()));
    // Direct lighting runs one path at a time: a wide backend is refused for it.
    let out = dir.path().join("refused.exr");
    let o = render_cmd(&out, 4, &["--backend", "avx2", "--integrator", "direct"])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("--backend avx2"));
    assert!(!out.exists(), "nothing written");
    let o = render_cmd(&out, 4, &["--backend", "sse9"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
}

/// A time budget spent while the photon maps are still being traced leaves no sample to
/// show: nothing is written (an existing output stays), exit 2 with a message that says so.
#[test]
fn photon_budget_spent_on_the_maps_writes_nothing() {
    let dir = TempDir::new("photon-budget");
    let out = dir.path().join("out.exr");
    std::fs::write(&out, b"keep").unwrap();
    let o = render_cmd(
        &out,
        4,
        &[
            "--integrator",
            "photon",
            "--photons",
            "2000000",
            "--time",
            "1ms",
        ],
    )
    .output()
    .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("photon maps"), "{err}");
    assert_eq!(
        std::fs::read(&out).unwrap(),
        b"keep",
        "the output was overwritten"
    );
}
