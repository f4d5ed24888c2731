//! The PLY reader: ASCII and both binary byte orders, every scalar type, texture-coordinate
//! naming variants, elements and properties it must read past, and its errors.

use glam::{Vec2, Vec3};
use mcrt::scene::ply::{load_ply, parse_ply, PlyMesh};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A fresh file path under the system temp dir, unique per process and test.
fn temp_file(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mcrt-ply-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn write(name: &str, bytes: &[u8]) -> PathBuf {
    let p = temp_file(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn load_bytes(name: &str, bytes: &[u8]) -> Result<PlyMesh, String> {
    let p = write(name, bytes);
    let r = load_ply(&p).map_err(|e| e.to_string());
    std::fs::remove_file(&p).ok();
    r
}

fn err_of(name: &str, bytes: &[u8]) -> String {
    match load_bytes(name, bytes) {
        Ok(m) => panic!("{name}: expected an error, got {m:?}"),
        Err(e) => {
            assert!(e.contains(name), "the error should name the file: {e}");
            e
        }
    }
}

/// Byte writer for binary PLY bodies.
struct Bin {
    big: bool,
    out: Vec<u8>,
}

impl Bin {
    fn new(header: &str, big: bool) -> Self {
        Bin {
            big,
            out: header.as_bytes().to_vec(),
        }
    }
    fn put(&mut self, le: &[u8], be: &[u8]) -> &mut Self {
        self.out.extend_from_slice(if self.big { be } else { le });
        self
    }
    fn i8(&mut self, v: i8) -> &mut Self {
        self.out.push(v as u8);
        self
    }
    fn u8(&mut self, v: u8) -> &mut Self {
        self.out.push(v);
        self
    }
    fn i16(&mut self, v: i16) -> &mut Self {
        self.put(&v.to_le_bytes(), &v.to_be_bytes())
    }
    fn u16(&mut self, v: u16) -> &mut Self {
        self.put(&v.to_le_bytes(), &v.to_be_bytes())
    }
    fn i32(&mut self, v: i32) -> &mut Self {
        self.put(&v.to_le_bytes(), &v.to_be_bytes())
    }
    fn u32(&mut self, v: u32) -> &mut Self {
        self.put(&v.to_le_bytes(), &v.to_be_bytes())
    }
    fn f32(&mut self, v: f32) -> &mut Self {
        self.put(&v.to_le_bytes(), &v.to_be_bytes())
    }
    fn f64(&mut self, v: f64) -> &mut Self {
        self.put(&v.to_le_bytes(), &v.to_be_bytes())
    }
}

/// The unit square in z = 0 as one quad, with normals +z and uvs at the corners.
fn square() -> PlyMesh {
    PlyMesh {
        positions: vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ],
        normals: vec![Vec3::Z; 4],
        uvs: vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ],
        indices: vec![[0, 1, 2], [0, 2, 3]],
    }
}

const ASCII_SQUARE: &str = "ply
format ascii 1.0
comment made by hand
obj_info a square
element vertex 4
property float x
property float y
property float z
property float nx
property float ny
property float nz
property float u
property float v
element face 1
property list uchar int vertex_indices
end_header
0 0 0 0 0 1 0 0
1 0 0 0 0 1 1 0
1 1 0 0 0 1 1 1
0 1 0 0 0 1 0 1
4 0 1 2 3
";

#[test]
fn ascii_quad_is_fanned() {
    let m = load_bytes("ascii_square.ply", ASCII_SQUARE.as_bytes()).unwrap();
    assert_eq!(m, square());
}

#[test]
fn ascii_crlf_header_and_body() {
    let text = ASCII_SQUARE.replace('\n', "\r\n");
    let m = load_bytes("ascii_crlf.ply", text.as_bytes()).unwrap();
    assert_eq!(m, square());
}

#[test]
fn polygon_fan_order_and_mixed_faces() {
    let text = "ply
format ascii 1.0
element vertex 5
property double x
property double y
property double z
element face 2
property list uchar uint vertex_index
end_header
0 0 0
1 0 0
2 1 0
1 2 0
0 1 0
5 0 1 2 3 4
3 4 3 2
";
    let m = load_bytes("pentagon.ply", text.as_bytes()).unwrap();
    assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [4, 3, 2]]);
    assert!(m.normals.is_empty());
    assert!(m.uvs.is_empty());
    assert_eq!(m.positions[2], Vec3::new(2.0, 1.0, 0.0));
}

#[test]
fn ascii_skips_unknown_elements_and_properties() {
    // An unknown element with a list property before the vertices, unknown vertex
    // properties (scalar and list) between the known ones, a face with extra properties,
    // and an unknown element after the faces.
    let text = "ply
format ascii 1.0
element material 2
property list ushort float coefficients
property uchar id
element vertex 3
property float x
property list uchar int junk
property float y
property uchar red
property float z
property float s
property float t
element face 1
property uchar flags
property list uchar int vertex_indices
property list uchar float texcoord
element edge 1
property int vertex1
property int vertex2
end_header
3 0.1 0.2 0.3 7
0 8
0 2 9 9 0 255 0 0.25 0.5
1 0 0 0 0 0.75 0.5
0 1 0 1 0 0 0.5 1
42 3 0 1 2 6 0 0 1 0 0 1
0 1
";
    let m = load_bytes("skips.ply", text.as_bytes()).unwrap();
    assert_eq!(
        m.positions,
        vec![
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0)
        ]
    );
    assert_eq!(
        m.uvs,
        vec![
            Vec2::new(0.25, 0.5),
            Vec2::new(0.75, 0.5),
            Vec2::new(0.5, 1.0)
        ]
    );
    assert!(m.normals.is_empty());
    assert_eq!(m.indices, vec![[0, 1, 2]]);
}

#[test]
fn uv_name_variants() {
    for (a, b) in [
        ("u", "v"),
        ("s", "t"),
        ("texture_u", "texture_v"),
        ("texture_s", "texture_t"),
    ] {
        let text = format!(
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
             property float z\nproperty float {a}\nproperty float {b}\nend_header\n1 2 3 0.25 0.75\n"
        );
        let m = load_bytes(&format!("uv_{a}.ply"), text.as_bytes()).unwrap();
        assert_eq!(m.uvs, vec![Vec2::new(0.25, 0.75)], "{a}/{b}");
        assert_eq!(m.positions, vec![Vec3::new(1.0, 2.0, 3.0)]);
    }
}

#[test]
fn uv_name_preference_follows_mitsuba() {
    // u/v first, then texture_u/texture_v, then s/t.
    let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                property float z\nproperty float s\nproperty float t\nproperty float texture_u\n\
                property float texture_v\nend_header\n0 0 0 0.1 0.2 0.3 0.4\n";
    let m = load_bytes("uv_pref.ply", text.as_bytes()).unwrap();
    assert_eq!(m.uvs, vec![Vec2::new(0.3, 0.4)]);
}

#[test]
fn normals_are_normalized() {
    let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
                end_header\n0 0 0 0 0 2\n";
    let m = load_bytes("normals.ply", text.as_bytes()).unwrap();
    assert_eq!(m.normals, vec![Vec3::Z]);
}

const BIN_HEADER: &str = "element vertex 4
property float x
property float y
property float z
property uchar red
property list uchar short junk
property double nx
property double ny
property double nz
property float texture_u
property float texture_v
element edge 2
property int vertex1
property list int uint8 stuff
element face 2
property int flags
property list uchar int vertex_indices
property list ushort double weights
end_header
";

fn binary_square(big: bool) -> Vec<u8> {
    let fmt = if big {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut b = Bin::new(
        &format!("ply\nformat {fmt} 1.0\ncomment binary\n{BIN_HEADER}"),
        big,
    );
    let sq = square();
    for i in 0..4 {
        let p = sq.positions[i];
        b.f32(p.x).f32(p.y).f32(p.z).u8(200);
        // A list of i+1 shorts, read past.
        b.u8(i as u8 + 1);
        for k in 0..=i {
            b.i16(-(k as i16));
        }
        b.f64(0.0).f64(0.0).f64(1.0);
        b.f32(sq.uvs[i].x).f32(sq.uvs[i].y);
    }
    // Two edges: a scalar and a list of bytes.
    b.i32(0).i32(2).u8(1).u8(2);
    b.i32(1).i32(0);
    // Faces: two triangles, each with flags and a list of doubles.
    b.i32(-1)
        .u8(3)
        .i32(0)
        .i32(1)
        .i32(2)
        .u16(2)
        .f64(0.5)
        .f64(0.5);
    b.i32(-1).u8(3).i32(0).i32(2).i32(3).u16(0);
    b.out.clone()
}

#[test]
fn binary_little_endian() {
    let m = load_bytes("le.ply", &binary_square(false)).unwrap();
    assert_eq!(m, square());
}

#[test]
fn binary_big_endian() {
    let m = load_bytes("be.ply", &binary_square(true)).unwrap();
    assert_eq!(m, square());
}

#[test]
fn every_scalar_type_in_both_byte_orders() {
    // Vertex properties in each type (both spellings), face lists with 16- and 32-bit counts.
    let header = |fmt: &str| {
        format!(
            "ply\nformat {fmt} 1.0\nelement vertex 3\n\
             property char x\nproperty uint8 y\nproperty int16 z\n\
             property ushort a\nproperty int32 b\nproperty uint c\n\
             property float32 nx\nproperty float64 ny\nproperty double nz\n\
             property int8 p\nproperty uchar q\nproperty short r\nproperty uint16 s0\n\
             property int t0\nproperty uint32 w\nproperty float k\n\
             element face 1\nproperty list uint16 uint8 vertex_indices\nend_header\n"
        )
    };
    let expect = [
        Vec3::new(-3.0, 250.0, -30000.0),
        Vec3::new(127.0, 0.0, 32767.0),
        Vec3::new(-128.0, 255.0, -32768.0),
    ];
    for big in [false, true] {
        let fmt = if big {
            "binary_big_endian"
        } else {
            "binary_little_endian"
        };
        let mut b = Bin::new(&header(fmt), big);
        for p in expect {
            b.i8(p.x as i8).u8(p.y as u8).i16(p.z as i16);
            b.u16(65535).i32(-7).u32(4_000_000_000);
            b.f32(0.0).f64(-1.0).f64(0.0);
            b.i8(1).u8(2).i16(3).u16(4).i32(5).u32(6).f32(7.0);
        }
        b.u16(3).u8(2).u8(1).u8(0);
        let m = load_bytes(&format!("types_{fmt}.ply"), &b.out).unwrap();
        assert_eq!(m.positions, expect.to_vec(), "{fmt}");
        assert_eq!(m.normals, vec![Vec3::NEG_Y; 3], "{fmt}");
        assert_eq!(m.indices, vec![[2, 1, 0]], "{fmt}");
    }
}

#[test]
fn into_triangle_mesh_keeps_geometry() {
    let tm = square().into_triangle_mesh();
    assert_eq!(tm.positions, square().positions);
    assert_eq!(tm.normals, Some(square().normals));
    assert_eq!(tm.indices, square().indices);
    let tm = PlyMesh {
        normals: vec![],
        ..square()
    }
    .into_triangle_mesh();
    assert!(tm.normals.is_none());
}

#[test]
fn parse_ply_from_memory() {
    let m = parse_ply(Path::new("mem.ply"), ASCII_SQUARE.as_bytes()).unwrap();
    assert_eq!(m, square());
}

// ---------------------------------------------------------------------------------------------
// Errors
// ---------------------------------------------------------------------------------------------

#[test]
fn missing_file() {
    let p = temp_file("does_not_exist.ply");
    let e = load_ply(&p).unwrap_err().to_string();
    assert!(
        e.contains("does_not_exist.ply") && e.contains("cannot read"),
        "{e}"
    );
}

#[test]
fn bad_magic_and_empty_file() {
    let e = err_of("magic.ply", b"PLY\nformat ascii 1.0\nend_header\n");
    assert!(e.contains(":1:1:") && e.contains("not a PLY file"), "{e}");
    let e = err_of("empty.ply", b"");
    assert!(e.contains("not a PLY file"), "{e}");
    let e = err_of("obj.ply", b"v 0 0 0\n");
    assert!(e.contains("not a PLY file"), "{e}");
}

#[test]
fn header_without_end() {
    let e = err_of(
        "noend.ply",
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n",
    );
    assert!(e.contains("end_header") && e.contains(":5:1:"), "{e}");
}

#[test]
fn unknown_format_and_version() {
    let e = err_of(
        "fmt.ply",
        b"ply\nformat binary_middle_endian 1.0\nend_header\n",
    );
    assert!(
        e.contains(":2:8:") && e.contains("unknown format 'binary_middle_endian'"),
        "{e}"
    );
    let e = err_of("ver.ply", b"ply\nformat ascii 2.0\nend_header\n");
    assert!(e.contains(":2:14:") && e.contains("version '2.0'"), "{e}");
    let e = err_of("nofmt.ply", b"ply\nelement vertex 0\nend_header\n");
    assert!(e.contains("no 'format'"), "{e}");
}

#[test]
fn header_errors() {
    let e = err_of(
        "type.ply",
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n",
    );
    assert!(
        e.contains(":4:10:") && e.contains("unknown property type 'float128'"),
        "{e}"
    );
    let e = err_of(
        "orphan.ply",
        b"ply\nformat ascii 1.0\nproperty float x\nend_header\n",
    );
    assert!(
        e.contains(":3:1:") && e.contains("before any 'element'"),
        "{e}"
    );
    let e = err_of(
        "count.ply",
        b"ply\nformat ascii 1.0\nelement vertex -4\nend_header\n",
    );
    assert!(e.contains(":3:16:") && e.contains("element count"), "{e}");
    let e = err_of(
        "kw.ply",
        b"ply\nformat ascii 1.0\nelephant vertex 4\nend_header\n",
    );
    assert!(e.contains(":3:1:") && e.contains("'elephant'"), "{e}");
    let e = err_of(
        "noxyz.ply",
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n",
    );
    assert!(e.contains(":3:1:") && e.contains("x, y and z"), "{e}");
    let e = err_of(
        "noidx.ply",
        b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int corners\nend_header\n3 0 0 0\n",
    );
    assert!(e.contains(":7:1:") && e.contains("vertex_indices"), "{e}");
}

#[test]
fn non_numeric_ascii_token() {
    let text = ASCII_SQUARE.replace("1 1 0 0 0 1 1 1", "1 1 0 0 zero 1 1 1");
    let e = err_of("nan_token.ply", text.as_bytes());
    // Line 19, column 9: the fifth field of the third vertex.
    assert!(e.contains(":19:9:"), "{e}");
    assert!(
        e.contains("'zero'") && e.contains("element 'vertex' 2") && e.contains("'ny'"),
        "{e}"
    );
    // A float where an integer index belongs.
    let text = ASCII_SQUARE.replace("4 0 1 2 3", "4 0 1.5 2 3");
    let e = err_of("float_index.ply", text.as_bytes());
    assert!(
        e.contains(":21:5:") && e.contains("integer") && e.contains("'1.5'"),
        "{e}"
    );
}

#[test]
fn index_out_of_range() {
    let text = ASCII_SQUARE.replace("4 0 1 2 3", "4 0 1 2 4");
    let e = err_of("range.ply", text.as_bytes());
    assert!(
        e.contains(":21:9:") && e.contains("out of range") && e.contains("4 vertices"),
        "{e}"
    );
    let text = ASCII_SQUARE.replace("4 0 1 2 3", "4 0 -1 2 3");
    let e = err_of("negative.ply", text.as_bytes());
    assert!(e.contains(":21:5:") && e.contains("out of range"), "{e}");
    // Binary: the byte offset of the bad index.
    let mut b = binary_square(false);
    let n = b.len();
    b[n - 6..n - 2].copy_from_slice(&9i32.to_le_bytes()); // second face's last index
    let e = err_of("range_le.ply", &b);
    assert!(
        e.contains(&format!("byte offset {}", n - 6))
            && e.contains("face 1")
            && e.contains("index 9"),
        "{e}"
    );
}

#[test]
fn faces_with_fewer_than_three_vertices() {
    let text = ASCII_SQUARE.replace("4 0 1 2 3", "2 0 1");
    let e = err_of("degenerate.ply", text.as_bytes());
    assert!(
        e.contains(":21:1:") && e.contains("face 0 has 2 vertices"),
        "{e}"
    );
    let text = ASCII_SQUARE.replace("4 0 1 2 3", "0");
    let e = err_of("empty_face.ply", text.as_bytes());
    assert!(e.contains("face 0 has 0 vertices"), "{e}");
}

#[test]
fn truncated_ascii() {
    let text = ASCII_SQUARE.replace("4 0 1 2 3\n", "4 0 1\n");
    let e = err_of("trunc.ply", text.as_bytes());
    assert!(
        e.contains("unexpected end") && e.contains("element 'face' 0") && e.contains(":22:1:"),
        "{e}"
    );
    let text = &ASCII_SQUARE[..ASCII_SQUARE.find("1 1 0 0 0 1 1 1").unwrap()];
    let e = err_of("trunc_v.ply", text.as_bytes());
    assert!(e.contains("element 'vertex' 2, property 'x'"), "{e}");
}

#[test]
fn truncated_binary_names_element_index_and_offset() {
    for big in [false, true] {
        let full = binary_square(big);
        let header_len = full.len() - {
            // Body size: 4 vertices + edges + faces, as written by binary_square.
            let v: usize = (0..4).map(|i| 12 + 1 + 1 + 2 * (i + 1) + 24 + 8).sum();
            v + (4 + 4 + 2) + 8 + (4 + 1 + 12 + 2 + 16) + (4 + 1 + 12 + 2)
        };
        assert_eq!(&full[header_len - 11..header_len], b"end_header\n");
        // Cut inside vertex 2 (after its position: 3 floats).
        let v2 = header_len + (12 + 1 + 1 + 2 + 24 + 8) + (12 + 1 + 1 + 4 + 24 + 8);
        let cut = &full[..v2 + 12];
        let e = err_of(&format!("trunc_v_{big}.ply"), cut);
        assert!(
            e.contains("truncated") && e.contains("element 'vertex' 2, property 'red'"),
            "{e}"
        );
        assert!(e.contains(&format!("byte offset {}", v2 + 12)), "{e}");
        // Cut in the middle of the last face's list of weights count.
        let cut = &full[..full.len() - 1];
        let e = err_of(&format!("trunc_f_{big}.ply"), cut);
        assert!(
            e.contains("truncated") && e.contains("element 'face' 1, property 'weights'"),
            "{e}"
        );
        // A skipped list whose items run past the end.
        let mut cut = full[..full.len() - 2].to_vec();
        cut.extend_from_slice(&if big { [0u8, 200] } else { [200u8, 0] });
        let e = err_of(&format!("trunc_list_{big}.ply"), &cut);
        assert!(
            e.contains("truncated") && e.contains("200 items") && e.contains("'weights'"),
            "{e}"
        );
    }
}

#[test]
fn huge_declared_counts_fail_fast() {
    let start = Instant::now();
    // Billions of vertices in a file of a few hundred bytes.
    let header = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n\
                  property float x\nproperty float y\nproperty float z\nend_header\n";
    let mut b = Bin::new(header, false);
    b.f32(1.0).f32(2.0).f32(3.0).f32(4.0);
    let e = err_of("huge_v.ply", &b.out);
    assert!(
        e.contains("truncated") && e.contains("element 'vertex' 1"),
        "{e}"
    );
    // A face list claiming 4 billion corners.
    let header = "ply\nformat binary_little_endian 1.0\nelement vertex 3\n\
                  property float x\nproperty float y\nproperty float z\n\
                  element face 1\nproperty list uint uint vertex_indices\nend_header\n";
    let mut b = Bin::new(header, false);
    for _ in 0..9 {
        b.f32(0.0);
    }
    b.u32(u32::MAX).u32(0).u32(1).u32(2);
    let e = err_of("huge_list.ply", &b.out);
    assert!(
        e.contains("truncated") && e.contains("element 'face' 0"),
        "{e}"
    );
    // An unknown element with a huge count and a huge skipped list, in ASCII.
    let text = "ply\nformat ascii 1.0\nelement junk 18446744073709551615\n\
                property list uint float values\nend_header\n4294967295 1 2 3\n";
    let e = err_of("huge_ascii.ply", text.as_bytes());
    assert!(
        e.contains("unexpected end") && e.contains("element 'junk' 0"),
        "{e}"
    );
    // More vertices than 32-bit indices can address.
    let text = "ply\nformat ascii 1.0\nelement vertex 4294967296\nproperty float x\n\
                property float y\nproperty float z\nend_header\n";
    let e = err_of("too_many.ply", text.as_bytes());
    assert!(e.contains(":3:1:") && e.contains("more than"), "{e}");
    // A count that does not fit in 64 bits.
    let text = "ply\nformat ascii 1.0\nelement vertex 99999999999999999999999\nend_header\n";
    let e = err_of("overflow.ply", text.as_bytes());
    assert!(e.contains("element count"), "{e}");
    assert!(start.elapsed().as_secs_f64() < 2.0, "{:?}", start.elapsed());
}

#[test]
fn non_finite_values_are_rejected() {
    let text = ASCII_SQUARE.replace("1 1 0 0 0 1 1 1", "1 inf 0 0 0 1 1 1");
    let e = err_of("inf.ply", text.as_bytes());
    assert!(e.contains(":19:3:") && e.contains("finite"), "{e}");
}
