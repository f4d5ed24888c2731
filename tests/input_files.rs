//! Hostile input files (issue 27): headers that claim more memory than there is, files that
//! are not regular files, forged checkpoints, texture values no constant could have, numbers
//! beyond f32, degenerate cameras, byte-order marks, and the messages about them. Each attack
//! is generated here (a few hundred bytes, or a PNG that compresses to little); where it is
//! about memory, mcrt runs under `ulimit -v`, so that an unchecked allocation aborts instead
//! of succeeding on a large machine.

mod common;

use common::cli::*;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Address space mcrt may take in the memory tests: 3 GiB, in KiB for `ulimit -v`.
const CAP_KIB: u64 = 3 << 20;

/// Runs mcrt with `args` under `ulimit -v CAP_KIB` (when `capped`) and a 60 s deadline (a
/// reader that blocks on a FIFO would otherwise hang the test).
fn run_limited(args: &[&OsStr], capped: bool) -> Output {
    run_capped(args, capped.then_some(CAP_KIB))
}

/// [`run_limited`] with an address-space cap of `cap` KiB.
fn run_capped(args: &[&OsStr], cap: Option<u64>) -> Output {
    let mut cmd = if let Some(cap) = cap {
        let mut c = Command::new("sh");
        c.arg("-c")
            .arg(format!("ulimit -v {cap} && exec \"$0\" \"$@\""))
            .arg(BIN);
        c
    } else {
        Command::new(BIN)
    };
    let mut child = cmd
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("cannot run mcrt");
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            let o = child.wait_with_output().unwrap();
            panic!("mcrt did not finish in 60 s; stderr:\n{}", stderr_of(&o));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// Checks a clean refusal: exit status 2, no panic or abort, every fragment in the message,
/// which stays short (a user's value is echoed cut short), and no output written.
fn refused(o: &Output, fragments: &[&str], out: &Path) {
    let err = stderr_of(o);
    assert!(!err.contains("panicked"), "mcrt panicked:\n{err}");
    assert_eq!(o.status.code(), Some(2), "exit status; stderr:\n{err}");
    for f in fragments {
        assert!(err.contains(f), "the message should say {f:?}:\n{err}");
    }
    assert!(
        err.len() < 600,
        "the message is {} bytes long:\n{err}",
        err.len()
    );
    assert!(!out.exists(), "an output was written");
}

fn args<'a>(v: &'a [&'a dyn AsRef<OsStr>]) -> Vec<&'a OsStr> {
    v.iter().map(|a| a.as_ref()).collect()
}

/// A camera, and a sphere whose lambert albedo is `albedo` (a number, or a texture's name
/// with its `[texture.NAME]` table in `extra`).
fn scene_toml(albedo: &str, extra: &str) -> String {
    format!(
        "[render]\nwidth = 4\nheight = 4\nspp = 1\n\n[[camera]]\nname = \"c\"\n\
         type = \"perspective\"\norigin = [0, 0, 5]\ntarget = [0, 0, 0]\nup = [0, 1, 0]\n\
         fov = 40\n\n{extra}\n[material.m]\ntype = \"lambert\"\nalbedo = {albedo}\n\n\
         [[shape]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n"
    )
}

fn texture_scene(dir: &TempDir, file: &Path) -> PathBuf {
    dir.write(
        "scene.toml",
        &scene_toml(
            "\"t\"",
            &format!(
                "[texture.t]\ntype = \"bitmap\"\nfile = {:?}\n",
                file.display().to_string()
            ),
        ),
    )
}

/// The header of a scanline OpenEXR file of `w` × `h` float RGB pixels without compression,
/// and no pixel data: about 330 bytes that claim w·h·12 bytes of pixels.
fn exr_header(w: i32, h: i32) -> Vec<u8> {
    let mut b = vec![0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0];
    let mut attr = |name: &str, kind: &str, value: &[u8]| {
        for s in [name, kind] {
            b.extend_from_slice(s.as_bytes());
            b.push(0);
        }
        b.extend_from_slice(&(value.len() as i32).to_le_bytes());
        b.extend_from_slice(value);
    };
    let mut ch = Vec::new();
    for c in ["B", "G", "R"] {
        ch.extend_from_slice(c.as_bytes());
        ch.push(0);
        ch.extend_from_slice(&2i32.to_le_bytes()); // FLOAT
        ch.extend_from_slice(&[0, 0, 0, 0]); // pLinear, reserved
        ch.extend_from_slice(&1i32.to_le_bytes());
        ch.extend_from_slice(&1i32.to_le_bytes());
    }
    ch.push(0);
    let window: Vec<u8> = [0, 0, w - 1, h - 1]
        .iter()
        .flat_map(|v: &i32| v.to_le_bytes())
        .collect();
    attr("channels", "chlist", &ch);
    attr("compression", "compression", &[0]);
    attr("dataWindow", "box2i", &window);
    attr("displayWindow", "box2i", &window);
    attr("lineOrder", "lineOrder", &[0]);
    attr("pixelAspectRatio", "float", &1f32.to_le_bytes());
    attr("screenWindowCenter", "v2f", &[0; 8]);
    attr("screenWindowWidth", "float", &1f32.to_le_bytes());
    b.push(0);
    // The first offsets of the table, pointing past the end.
    for _ in 0..4 {
        b.extend_from_slice(&(1u64 << 40).to_le_bytes());
    }
    b
}

/// Class 1: an EXR whose header claims 100000 × 100000 pixels is refused before its pixels
/// are allocated, wherever mcrt reads an EXR: as a texture, by compare, merge and --resume.
/// (On the main branch of 2026-12-03 each aborted on a 40-120 GB allocation.)
#[test]
fn exr_header_claiming_huge_size_is_refused_everywhere() {
    let dir = TempDir::new("exr-huge");
    let exr = dir.path().join("huge.exr");
    std::fs::write(&exr, exr_header(100_000, 100_000)).unwrap();
    let out = dir.path().join("out.exr");
    let claim = ["100000 × 100000", "memory"];

    let scene = texture_scene(&dir, &exr);
    let o = run_limited(&args(&[&"render", &scene, &"-o", &out]), true);
    refused(&o, &[&claim[..], &["huge.exr"]].concat(), &out);

    let o = run_limited(&args(&[&"compare", &exr, &exr]), true);
    refused(&o, &[&claim[..], &["huge.exr"]].concat(), &out);

    let o = run_limited(&args(&[&"merge", &exr, &"-o", &out]), true);
    refused(&o, &[&claim[..], &["huge.exr"]].concat(), &out);

    let o = run_limited(
        &args(&[&"render", &scene, &"-o", &out, &"--resume", &exr]),
        true,
    );
    // The scene's texture is read first; a scene without one reaches the checkpoint.
    refused(&o, &claim, &out);
    let plain = dir.write("plain.toml", &scene_toml("0.5", ""));
    let o = run_limited(
        &args(&[&"render", &plain, &"-o", &out, &"--resume", &exr]),
        true,
    );
    refused(&o, &[&claim[..], &["huge.exr"]].concat(), &out);
}

/// Class 1, found by the `sums` fuzz target: a 2 kB sums file of 4 ZIP-compressed lines of
/// 3.6 M pixels. The fuzzer (under 4 GiB) found its layer and film within the budget but the
/// decoder's buffer for one block (1.7 GB) beyond: the memory check counts the decoder's
/// working memory too. (Under 3 GiB the main branch of 2026-12-03 aborts on it.)
#[test]
fn exr_block_buffers_count_in_the_memory_check() {
    let dir = TempDir::new("exr-block");
    let file =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz/sums-wide-zip-block.exr");
    let out = dir.path().join("out.png");
    let o = run_limited(&args(&[&"merge", &file, &"-o", &out]), true);
    refused(&o, &["sums-wide-zip-block.exr", "pixels", "memory"], &out);
}

/// Class 1: a PNG texture of 16384² 16-bit grey pixels (a small file: all zeros) decodes
/// to 512 MiB of samples and 3 GiB of linear pixels: refused by the memory check, named with
/// its size, not an abort under a 3 GiB address space. (16-bit images are kept as floats;
/// 8-bit ones as bytes, which at this size would fit.)
#[test]
fn png_texture_larger_than_memory_is_refused() {
    let dir = TempDir::new("png-huge");
    let png_path = dir.path().join("big.png");
    let n = 16384u32;
    {
        let f = std::io::BufWriter::new(std::fs::File::create(&png_path).unwrap());
        let mut enc = png::Encoder::new(f, n, n);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Sixteen);
        enc.set_compression(png::Compression::Fast);
        let mut w = enc.write_header().unwrap().into_stream_writer().unwrap();
        let row = vec![0u8; 2 * n as usize];
        for _ in 0..n {
            std::io::Write::write_all(&mut w, &row).unwrap();
        }
        w.finish().unwrap();
    }
    let scene = texture_scene(&dir, &png_path);
    let out = dir.path().join("out.png");
    let o = run_limited(&args(&[&"render", &scene, &"-o", &out]), true);
    refused(&o, &["big.png", "16384 × 16384", "memory"], &out);
}

/// Class 1: `--pass K/N` has a documented bound on N (the merge's per-pass state was sized
/// by it: `--pass 1/4000000000` was accepted and its merge aborted).
#[test]
fn pass_count_is_bounded() {
    let dir = TempDir::new("pass-bound");
    let scene = dir.write("s.toml", &scene_toml("0.5", ""));
    let out = dir.path().join("part.exr");
    let o = run_limited(
        &args(&[&"render", &scene, &"-o", &out, &"--pass", &"1/4000000000"]),
        true,
    );
    let err = stderr_of(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("at most 65536 passes"), "{err}");
    assert!(!out.exists());
    // mcrt's own message echoes a long value cut short (the flag parser quotes it whole
    // before it).
    let long = format!("1/{}", "9".repeat(5000));
    let o = run(&args(&[&"render", &scene, &"-o", &out, &"--pass", &long]));
    let err = stderr_of(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("got '1/999999999"), "{err}");
    assert!(err.contains("… (5002 characters)'"), "{err}");
}

fn mkfifo(path: &Path) {
    let ok = Command::new("mkfifo").arg(path).status().unwrap().success();
    assert!(ok, "mkfifo failed");
}

/// Class 4 and 9: a scene, an `<include>`, a mesh or a texture that is a FIFO, a character
/// device or a directory is refused at once, saying what it is (it blocked forever, read
/// until memory ran out, or was "not found").
#[test]
fn special_files_are_refused_as_what_they_are() {
    let dir = TempDir::new("special");
    let out = dir.path().join("out.png");
    let fifo = dir.path().join("pipe.toml");
    mkfifo(&fifo);
    let o = run_limited(&args(&[&"render", &fifo, &"-o", &out]), true);
    refused(
        &o,
        &["pipe.toml", "is a FIFO (named pipe), not a regular file"],
        &out,
    );

    let zero = dir.path().join("zero.toml");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let o = run_limited(&args(&[&"render", &zero, &"-o", &out]), true);
    refused(&o, &["zero.toml", "is a character device"], &out);

    let d = dir.path().join("dir.toml");
    std::fs::create_dir(&d).unwrap();
    let o = run_limited(&args(&[&"render", &d, &"-o", &out]), true);
    refused(&o, &["dir.toml", "is a directory"], &out);

    // An include that is a FIFO.
    let inc = dir.path().join("inc.xml");
    mkfifo(&inc);
    let xml = dir.write(
        "scene.xml",
        "<scene version=\"3.0.0\">\n<include filename=\"inc.xml\"/>\n</scene>\n",
    );
    let o = run_limited(&args(&[&"render", &xml, &"-o", &out]), true);
    refused(&o, &["scene.xml:2:", "inc.xml", "is a FIFO"], &out);

    // Meshes and textures: a FIFO and /dev/zero, not "not found".
    let mesh_fifo = dir.path().join("m.obj");
    mkfifo(&mesh_fifo);
    let mesh_zero = dir.path().join("z.ply");
    std::os::unix::fs::symlink("/dev/zero", &mesh_zero).unwrap();
    for (mesh, what) in [
        (&mesh_fifo, "is a FIFO"),
        (&mesh_zero, "is a character device"),
    ] {
        let s = dir.write(
            "mesh.toml",
            &format!(
                "{}\n[[shape]]\ntype = \"mesh\"\nfile = {:?}\nmaterial = \"m\"\n",
                scene_toml("0.5", ""),
                mesh.file_name().unwrap().to_string_lossy()
            ),
        );
        let o = run_limited(&args(&[&"render", &s, &"-o", &out]), true);
        refused(&o, &["mesh.toml", what], &out);
        let x = dir.write(
            "mesh.xml",
            &format!(
                "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><float name=\"fov\" \
                 value=\"40\"/></sensor>\n<shape type=\"{}\"><string name=\"filename\" \
                 value=\"{}\"/></shape>\n</scene>\n",
                mesh.extension().unwrap().to_string_lossy(),
                mesh.file_name().unwrap().to_string_lossy()
            ),
        );
        let o = run_limited(&args(&[&"render", &x, &"-o", &out]), true);
        refused(&o, &["mesh.xml", what], &out);
    }
    let tex_fifo = dir.path().join("t.png");
    mkfifo(&tex_fifo);
    let s = texture_scene(&dir, &tex_fifo);
    let o = run_limited(&args(&[&"render", &s, &"-o", &out]), true);
    refused(&o, &["scene.toml", "is a FIFO"], &out);

    // Checkpoints and images to compare.
    let ck = dir.path().join("ck.exr");
    mkfifo(&ck);
    let plain = dir.write("plain.toml", &scene_toml("0.5", ""));
    let o = run_limited(
        &args(&[&"render", &plain, &"-o", &out, &"--resume", &ck]),
        true,
    );
    refused(&o, &["ck.exr", "is a FIFO"], &out);
    let o = run_limited(&args(&[&"compare", &ck, &ck]), true);
    refused(&o, &["ck.exr", "is a FIFO"], &out);
    let o = run_limited(&args(&[&"merge", &ck, &"-o", &out]), true);
    refused(&o, &["ck.exr", "is a FIFO"], &out);
}

/// Writes an EXR texture of 2 × 2 pixels, all `v`.
fn exr_texture(dir: &TempDir, name: &str, v: f32) -> PathBuf {
    let p = dir.path().join(name);
    let img = mcrt::image::Image {
        width: 2,
        height: 2,
        pixels: vec![mcrt::Color::new(0.5, v, 0.5); 4],
    };
    mcrt::image::write_image(&p, &img, &Default::default()).unwrap();
    p
}

/// Class 8: texture values obey the rule of constants, texel by texel: negative, NaN,
/// infinite values are refused in both formats; a TOML reflectance above 1 too (a constant
/// above 1 is refused there), while Mitsuba XML, which takes reflectances above 1, takes
/// such a texture as it takes such a constant.
#[test]
fn texture_values_obey_the_constants_rule() {
    let dir = TempDir::new("texels");
    let out = dir.path().join("out.png");
    for (v, what) in [
        (-0.25, "finite and not negative"),
        (f32::NAN, "finite and not negative"),
        (f32::INFINITY, "finite and not negative"),
        (2.0, "at most 1"),
        (1e30, "at most 1"),
    ] {
        let tex = exr_texture(&dir, "t.exr", v);
        let s = texture_scene(&dir, &tex);
        let o = run(&args(&[&"render", &s, &"-o", &out]));
        refused(&o, &["scene.toml", what], &out);
        let x = dir.write(
            "scene.xml",
            &format!(
                "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><float name=\"fov\" \
                 value=\"40\"/><film type=\"hdrfilm\"><integer name=\"width\" value=\"4\"/>\
                 <integer name=\"height\" value=\"4\"/></film></sensor>\n<shape type=\"sphere\">\
                 <point name=\"center\" x=\"0\" y=\"0\" z=\"-5\"/><bsdf type=\"diffuse\">\
                 <texture type=\"bitmap\" name=\"reflectance\"><string name=\"filename\" \
                 value=\"{}\"/></texture></bsdf></shape>\n</scene>\n",
                tex.display()
            ),
        );
        let o = run(&args(&[&"render", &x, &"-o", &out, &"--spp", &"1"]));
        if v >= 0.0 && v.is_finite() {
            assert_eq!(o.status.code(), Some(0), "{}", stderr_of(&o));
            std::fs::remove_file(&out).unwrap();
        } else {
            refused(&o, &["scene.xml", "t.exr", what], &out);
        }
    }
}

/// Class 8: an OBJ file that starts with a UTF-8 byte-order mark renders as the same mesh
/// without it (the mark made the first vertex an unknown statement, shifting every index).
#[test]
fn obj_with_byte_order_mark_is_the_same_mesh() {
    let dir = TempDir::new("bom");
    let body = "v -1 -1 2\nv 1 -1 2\nv -1 1 2\nv 1 1 2\nf 1 2 3\nf 2 4 3\n";
    let mut images = Vec::new();
    for (name, text) in [
        ("plain", body.to_string()),
        ("bom", format!("\u{feff}{body}")),
    ] {
        let mesh = dir.write(&format!("{name}.obj"), &text);
        let s = dir.write(
            &format!("{name}.toml"),
            &format!(
                "{}\n[[shape]]\ntype = \"mesh\"\nfile = {:?}\nmaterial = \"m\"\n",
                scene_toml("0.5", ""),
                mesh.display().to_string()
            ),
        );
        let out = dir.path().join(format!("{name}.exr"));
        let o = run(&args(&[&"render", &s, &"-o", &out, &"-q"]));
        assert_eq!(o.status.code(), Some(0), "{name}: {}", stderr_of(&o));
        images.push(std::fs::read(&out).unwrap());
    }
    assert!(
        images[0] == images[1],
        "the byte-order mark changed the mesh"
    );
}

/// Renders `scene` at 8 × 8, 2 spp, writing a checkpoint; returns (output, checkpoint).
fn render_with_checkpoint(dir: &TempDir, scene: &Path, extra: &[&str]) -> (PathBuf, PathBuf) {
    let out = dir.path().join("out.exr");
    let ck = dir.path().join("ck.exr");
    let base: [&dyn AsRef<OsStr>; 12] = [
        &"render",
        &scene,
        &"-o",
        &out,
        &"--checkpoint",
        &ck,
        &"--spp",
        &"2",
        &"--width",
        &"8",
        &"--height",
        &"8",
    ];
    let mut a: Vec<&OsStr> = args(&base);
    a.push(OsStr::new("-q"));
    a.extend(extra.iter().map(OsStr::new));
    let o = run(&a);
    assert_eq!(o.status.code(), Some(0), "{}", stderr_of(&o));
    (out, ck)
}

/// Rewrites a checkpoint's `next` channel (every pixel + `add`), keeping its metadata.
fn forge_next(ck: &Path, add: u32) {
    use exr::prelude::*;
    let mut img = read_all_flat_layers_from_file(ck).unwrap();
    for ch in img.layer_data[0].channel_data.list.iter_mut() {
        if ch.name.eq("next") {
            let FlatSamples::U32(v) = &mut ch.sample_data else {
                panic!("next is not u32")
            };
            v.iter_mut().for_each(|n| *n += add);
        }
    }
    img.write().to_file(ck).unwrap();
}

/// Class 8: a checkpoint whose `next` channel claims more samples than its sums hold is
/// refused (its channels no longer match their checksum), as is one whose counts disagree
/// with its metadata; a settings mismatch names the setting, briefly (it printed two
/// 600-character strings).
#[test]
fn forged_or_mismatched_checkpoints_are_refused() {
    let resume = |scene: &Path, out: &Path, ck: &Path| {
        run(&args(&[
            &"render",
            &scene,
            &"-o",
            &out,
            &"--resume",
            &ck,
            &"--spp",
            &"8",
            &"--width",
            &"8",
            &"--height",
            &"8",
            &"-q",
        ]))
    };
    let dir = TempDir::new("forged");
    let scene = dir.write("s.toml", &scene_toml("0.5", ""));
    let (out, ck) = render_with_checkpoint(&dir, &scene, &[]);
    forge_next(&ck, 3);
    std::fs::remove_file(&out).unwrap();
    let o = resume(&scene, &out, &ck);
    refused(&o, &["ck.exr", "checksum"], &out);

    // Written with a valid checksum, but the channel disagrees with the metadata.
    let (out, ck) = render_with_checkpoint(&dir, &scene, &[]);
    let (part, mut more) = mcrt::parts::read_part_with(&ck, &["next"]).unwrap();
    more[0].iter_mut().for_each(|n| *n += 3);
    mcrt::parts::write_part_with(&ck, &part, &[("next", &more[0])]).unwrap();
    std::fs::remove_file(&out).unwrap();
    let o = resume(&scene, &out, &ck);
    refused(&o, &["ck.exr", "'next' channel holds 5 to 5 samples"], &out);

    let (out, ck) = render_with_checkpoint(&dir, &scene, &["--shadow-rays", "1"]);
    std::fs::remove_file(&out).unwrap();
    let o = run(&args(&[
        &"render",
        &scene,
        &"-o",
        &out,
        &"--resume",
        &ck,
        &"--spp",
        &"8",
        &"--width",
        &"8",
        &"--height",
        &"8",
        &"-q",
        &"--shadow-rays",
        &"4",
    ]));
    refused(&o, &["shadow_rays: 1", "shadow_rays: 4"], &out);
    assert!(stderr_of(&o).len() < 300, "{}", stderr_of(&o));
}
