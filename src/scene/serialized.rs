//! Mitsuba's `serialized` meshes, format versions 3 and 4 (what Mitsuba 0.5–0.6 and Mitsuba
//! 3 up to 3.9 write and read; layout from Mitsuba 3's src/shapes/serialized.cpp,
//! `load_legacy`).
//!
//! A file is one or more meshes one after the other, then a table of where each begins.
//! Each mesh: an uncompressed header (u16 0x041C, u16 version), then a zlib stream holding
//! a u32 flag word (0x1 vertex normals, 0x2 texture coordinates, 0x8 vertex colours, 0x2000
//! double precision), the mesh's NUL-terminated name (version 4 only), the vertex and
//! triangle counts (u64), the positions, normals, texture coordinates and colours of the
//! vertices, and three u32 indices per triangle. The table at the end gives each mesh's
//! offset (u64 in version 4, u32 in version 3) and then their number (u32). Little endian
//! throughout.
//!
//! Counts are never trusted for allocation beyond what the memory check allows: arrays grow
//! with the data the stream actually holds, so a short file that claims a billion vertices
//! fails at its end. Every index is checked against the vertex count and every position
//! must be finite.

use super::SceneError;
use crate::geometry::mesh::TriangleMesh;
use flate2::read::ZlibDecoder;
use glam::{Vec2, Vec3};
use std::io::Read;
use std::path::Path;

/// The first two bytes of every mesh in the file.
const MAGIC: u16 = 0x041C;
const HAS_NORMALS: u32 = 0x0001;
const HAS_TEXCOORDS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
const DOUBLE_PRECISION: u32 = 0x2000;
/// Longest mesh name read (the name is not used; it only has to end).
const MAX_NAME: usize = 1 << 16;

/// Reads mesh `shape_index` of a serialized file. The mesh has the file's normals (None
/// without), texture coordinates as stored (no flip of v) and its triangles.
pub fn load_serialized(path: &Path, shape_index: u32) -> Result<TriangleMesh, SceneError> {
    let data = crate::input::read(path)
        .map_err(|e| SceneError::new(path, None, format!("cannot read mesh file: {e}")))?;
    parse_serialized(&data, shape_index).map_err(|e| SceneError::new(path, None, e))
}

/// Parses the bytes of a serialized file; Err says what is wrong, without the path.
pub fn parse_serialized(data: &[u8], shape_index: u32) -> Result<TriangleMesh, String> {
    let version = header(data, 0)?;
    let start = if shape_index == 0 {
        0
    } else {
        mesh_offset(data, version, shape_index)?
    };
    if start != 0 && header(data, start)? != version {
        return Err(format!(
            "mesh {shape_index} (at byte {start}) has another format version than the file's \
             first ({version})"
        ));
    }
    let mut z = Stream {
        inner: ZlibDecoder::new(&data[start + 4..]),
        what: "",
    };
    read_mesh(&mut z, version)
}

/// The format version of the mesh header at byte `at`, after checking its magic number.
fn header(data: &[u8], at: usize) -> Result<u16, String> {
    let Some(h) = data.get(at..at + 4) else {
        return Err(format!(
            "the file is truncated: {} bytes, too short for a mesh header at byte {at}",
            data.len()
        ));
    };
    let magic = u16::from_le_bytes([h[0], h[1]]);
    let version = u16::from_le_bytes([h[2], h[3]]);
    if magic != MAGIC {
        return Err(format!(
            "not a Mitsuba serialized mesh: the header at byte {at} starts with 0x{magic:04X}, \
             not 0x{MAGIC:04X}"
        ));
    }
    if version != 3 && version != 4 {
        return Err(format!(
            "format version {version} is not supported (mcrt reads versions 3 and 4, which \
             Mitsuba 0.5 to 3.9 write)"
        ));
    }
    Ok(version)
}

/// Where mesh `index` (> 0) begins, from the table at the end of the file.
fn mesh_offset(data: &[u8], version: u16, index: u32) -> Result<usize, String> {
    let n = data.len();
    let word = |at: usize, len: usize| -> Option<u64> {
        let b = data.get(at..at.checked_add(len)?)?;
        let mut v = [0u8; 8];
        v[..len].copy_from_slice(b);
        Some(u64::from_le_bytes(v))
    };
    let count = n
        .checked_sub(4)
        .and_then(|at| word(at, 4))
        .ok_or("the file is too short for its table of meshes")?;
    if index as u64 >= count {
        return Err(format!(
            "shape_index {index} is out of range: the file holds {count} mesh{} (0..{})",
            if count == 1 { "" } else { "es" },
            count.saturating_sub(1)
        ));
    }
    let entry = if version >= 4 { 8 } else { 4 };
    // Entry `index` of `count`, which end just before the count.
    let back = (count - index as u64)
        .checked_mul(entry)
        .and_then(|b| b.checked_add(4))
        .filter(|&b| b <= n as u64)
        .ok_or_else(|| {
            format!("the file's table of {count} meshes does not fit in its {n} bytes")
        })?;
    let at = n - back as usize;
    let offset = word(at, entry as usize).unwrap_or(u64::MAX);
    if offset >= at as u64 {
        return Err(format!(
            "the table says mesh {index} begins at byte {offset}, past the meshes' data \
             (which end at byte {at})"
        ));
    }
    Ok(offset as usize)
}

/// The decompressed stream of one mesh, read field by field.
struct Stream<R: Read> {
    inner: R,
    /// The field being read, for the message should the stream end or be corrupt.
    what: &'static str,
}

impl<R: Read> Stream<R> {
    fn bytes<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let mut b = [0u8; N];
        self.inner.read_exact(&mut b).map_err(|e| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                format!(
                    "the compressed data ends in the {}: the file is truncated",
                    self.what
                )
            } else {
                format!("the compressed data is corrupt (in the {}): {e}", self.what)
            }
        })?;
        Ok(b)
    }

    fn u32(&mut self) -> Result<u32, String> {
        self.bytes::<4>().map(u32::from_le_bytes)
    }

    fn u64(&mut self) -> Result<u64, String> {
        self.bytes::<8>().map(u64::from_le_bytes)
    }

    fn real(&mut self, double: bool) -> Result<f32, String> {
        if double {
            Ok(f64::from_le_bytes(self.bytes::<8>()?) as f32)
        } else {
            Ok(f32::from_le_bytes(self.bytes::<4>()?))
        }
    }

    fn vec3(&mut self, double: bool) -> Result<Vec3, String> {
        Ok(Vec3::new(
            self.real(double)?,
            self.real(double)?,
            self.real(double)?,
        ))
    }

    /// `n` items read by `item`, in a vector that grows with what the stream holds.
    fn array<T>(
        &mut self,
        what: &'static str,
        n: u64,
        mut item: impl FnMut(&mut Self) -> Result<T, String>,
    ) -> Result<Vec<T>, String> {
        self.what = what;
        let mut v = Vec::with_capacity(n.min(1 << 16) as usize);
        for _ in 0..n {
            v.push(item(self)?);
        }
        Ok(v)
    }
}

fn read_mesh<R: Read>(z: &mut Stream<R>, version: u16) -> Result<TriangleMesh, String> {
    z.what = "flags";
    let flags = z.u32()?;
    if version >= 4 {
        z.what = "mesh name";
        let mut len = 0;
        while z.bytes::<1>()?[0] != 0 {
            len += 1;
            if len > MAX_NAME {
                return Err(format!("the mesh's name is longer than {MAX_NAME} bytes"));
            }
        }
    }
    z.what = "vertex and triangle counts";
    let (nv, nf) = (z.u64()?, z.u64()?);
    if nv >= u32::MAX as u64 || nf > super::desc::MAX_PRIMITIVES as u64 {
        return Err(format!(
            "the mesh claims {nv} vertices and {nf} triangles; mcrt reads at most {} and {}",
            u32::MAX - 1,
            super::desc::MAX_PRIMITIVES
        ));
    }
    let double = flags & DOUBLE_PRECISION != 0;
    let real = if double { 8 } else { 4 };
    let per_vertex = 3 * real
        + if flags & HAS_NORMALS != 0 {
            3 * real
        } else {
            0
        }
        + if flags & HAS_TEXCOORDS != 0 {
            2 * real
        } else {
            0
        };
    crate::check_allocation(nv * per_vertex + nf * 12)
        .map_err(|e| format!("the mesh of {nv} vertices and {nf} triangles {e}"))?;
    let positions = z.array("positions", nv, |z| z.vec3(double))?;
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(format!(
            "vertex {i} has a position that is not a finite number"
        ));
    }
    let normals = if flags & HAS_NORMALS != 0 {
        let ns = z.array("normals", nv, |z| z.vec3(double))?;
        // A zero or non-finite normal falls back to the face's (as a zero normal does in
        // `Scene::interaction`).
        Some(ns.into_iter().map(|n| n.normalize_or_zero()).collect())
    } else {
        None
    };
    let uvs = if flags & HAS_TEXCOORDS != 0 {
        Some(z.array("texture coordinates", nv, |z| {
            Ok(Vec2::new(z.real(double)?, z.real(double)?))
        })?)
    } else {
        None
    };
    if flags & HAS_COLORS != 0 {
        z.array("vertex colours", nv, |z| z.vec3(double))?;
    }
    let indices = z.array("triangles", nf, |z| Ok([z.u32()?, z.u32()?, z.u32()?]))?;
    if let Some((i, t)) = indices
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&k| k as u64 >= nv))
    {
        return Err(format!(
            "triangle {i} refers to vertex {}, but the mesh has {nv} vertices",
            t.iter().max().unwrap_or(&0)
        ));
    }
    Ok(TriangleMesh {
        tangents: None,
        positions,
        normals,
        uvs,
        indices,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A mesh in the format, as tools/write_serialized.py writes it.
    fn mesh(version: u16, flags: u32, body: &[u8]) -> Vec<u8> {
        let mut raw = flags.to_le_bytes().to_vec();
        if version == 4 {
            raw.extend_from_slice(b"m\0");
        }
        raw.extend_from_slice(body);
        let mut out = MAGIC.to_le_bytes().to_vec();
        out.extend_from_slice(&version.to_le_bytes());
        let mut e = flate2::write::ZlibEncoder::new(out, flate2::Compression::default());
        std::io::Write::write_all(&mut e, &raw).unwrap();
        e.finish().unwrap()
    }

    /// One triangle: counts, positions (single precision), indices.
    fn triangle(indices: [u32; 3]) -> Vec<u8> {
        let mut b = Vec::new();
        b.extend_from_slice(&3u64.to_le_bytes());
        b.extend_from_slice(&1u64.to_le_bytes());
        for v in [0.0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for i in indices {
            b.extend_from_slice(&i.to_le_bytes());
        }
        b
    }

    fn file(version: u16, meshes: &[Vec<u8>]) -> Vec<u8> {
        let mut out = Vec::new();
        let mut offsets = Vec::new();
        for m in meshes {
            offsets.push(out.len() as u64);
            out.extend_from_slice(m);
        }
        for o in offsets {
            if version == 4 {
                out.extend_from_slice(&o.to_le_bytes());
            } else {
                out.extend_from_slice(&(o as u32).to_le_bytes());
            }
        }
        out.extend_from_slice(&(meshes.len() as u32).to_le_bytes());
        out
    }

    #[test]
    fn both_versions_and_every_mesh() {
        for version in [3, 4] {
            let a = mesh(version, 0x1000, &triangle([0, 1, 2]));
            let b = mesh(version, 0x1000, &triangle([2, 1, 0]));
            let f = file(version, &[a, b]);
            let m0 = parse_serialized(&f, 0).unwrap();
            let m1 = parse_serialized(&f, 1).unwrap();
            assert_eq!(m0.indices, vec![[0, 1, 2]]);
            assert_eq!(m1.indices, vec![[2, 1, 0]]);
            assert_eq!(m1.positions[1], Vec3::X);
            assert!(m0.normals.is_none() && m0.uvs.is_none());
            let e = parse_serialized(&f, 2).unwrap_err();
            assert!(e.contains("shape_index 2 is out of range"), "{e}");
        }
    }

    #[test]
    fn the_committed_test_file() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/mitsuba/features/mesh.serialized");
        let tetra = load_serialized(&path, 0).unwrap();
        assert_eq!((tetra.positions.len(), tetra.indices.len()), (4, 4));
        let octa = load_serialized(&path, 1).unwrap();
        assert_eq!((octa.positions.len(), octa.indices.len()), (6, 8));
        let ns = octa.normals.unwrap();
        assert!(ns.iter().zip(&octa.positions).all(|(n, p)| *n == *p));
        assert_eq!(octa.uvs.unwrap()[0], Vec2::new(1.0, 0.5));
    }

    /// Double precision, and normals, texture coordinates and vertex colours (skipped).
    #[test]
    fn double_precision_with_every_attribute() {
        let mut b = Vec::new();
        b.extend_from_slice(&3u64.to_le_bytes());
        b.extend_from_slice(&1u64.to_le_bytes());
        let positions = [0.0f64, 0., 0., 2., 0., 0., 0., 2., 0.];
        let normals = [0.0f64, 0., 2., 0., 0., 1., 0., 0., 1.];
        let uvs = [0.0f64, 0., 1., 0., 0., 1.];
        let colours = [0.5f64; 9];
        for v in positions.iter().chain(&normals).chain(&uvs).chain(&colours) {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for i in [0u32, 1, 2] {
            b.extend_from_slice(&i.to_le_bytes());
        }
        let flags = DOUBLE_PRECISION | HAS_NORMALS | HAS_TEXCOORDS | HAS_COLORS;
        for version in [3, 4] {
            let m = parse_serialized(&file(version, &[mesh(version, flags, &b)]), 0).unwrap();
            assert_eq!(m.positions[1], Vec3::new(2.0, 0.0, 0.0));
            assert_eq!(m.normals.as_ref().unwrap()[0], Vec3::Z);
            assert_eq!(m.uvs.as_ref().unwrap()[2], Vec2::Y);
            assert_eq!(m.indices, vec![[0, 1, 2]]);
        }
    }

    /// The fuzz target's property on every cut and many byte changes of the test file:
    /// an answer, never a panic, and a mesh only with indices in range.
    #[test]
    fn mutations_never_panic() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/mitsuba/features/mesh.serialized");
        let good = std::fs::read(path).unwrap();
        let check = |data: &[u8]| {
            for index in 0..3 {
                if let Ok(m) = parse_serialized(data, index) {
                    let n = m.positions.len() as u32;
                    assert!(m.indices.iter().flatten().all(|&i| i < n));
                }
            }
        };
        for len in 0..good.len() {
            check(&good[..len]);
        }
        let mut rng = crate::sampler::Sampler::from_state(1, 2);
        for _ in 0..3000 {
            let mut d = good.clone();
            for _ in 0..1 + rng.next_u32() % 3 {
                let at = rng.next_u32() as usize % d.len();
                d[at] = rng.next_u32() as u8;
            }
            check(&d);
        }
    }

    #[test]
    fn bad_files_are_refused() {
        let good = file(4, &[mesh(4, 0x1000, &triangle([0, 1, 2]))]);
        let err = |data: &[u8], index| parse_serialized(data, index).unwrap_err();
        assert!(err(&good[..3], 0).contains("too short"));
        let mut magic = good.clone();
        magic[0] = 0x1D;
        assert!(err(&magic, 0).contains("not a Mitsuba serialized mesh"));
        let mut v5 = good.clone();
        v5[2] = 5;
        assert!(err(&v5, 0).contains("version 5 is not supported"));
        // Cut inside the compressed stream.
        assert!(
            err(&good[..20], 0).contains("truncated"),
            "{}",
            err(&good[..20], 0)
        );
        let mut corrupt = good.clone();
        for b in &mut corrupt[6..12] {
            *b ^= 0x5a;
        }
        let e = err(&corrupt, 0);
        assert!(e.contains("corrupt") || e.contains("truncated"), "{e}");
        let oob = file(4, &[mesh(4, 0x1000, &triangle([0, 1, 3]))]);
        assert!(err(&oob, 0).contains("refers to vertex 3"));
        // A count of meshes that the file cannot hold.
        let mut table = good.clone();
        let n = table.len();
        table[n - 4..].copy_from_slice(&1000u32.to_le_bytes());
        assert!(
            err(&table, 5).contains("does not fit"),
            "{}",
            err(&table, 5)
        );
        // A billion claimed vertices in a tiny file fail at the stream's end, not in memory.
        let mut huge = 1_000_000_000u64.to_le_bytes().to_vec();
        huge.extend_from_slice(&1u64.to_le_bytes());
        let lying = file(4, &[mesh(4, 0x1000, &huge)]);
        let e = err(&lying, 0);
        assert!(e.contains("truncated") || e.contains("memory"), "{e}");
    }
}
