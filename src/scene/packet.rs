//! Closest hits of up to sixteen rays from one origin, as a pinhole camera's rays are
//! ([`Scene::intersect_packet`]), in one traversal of the tree for all of them
//! ([`crate::accel::WideBvh::closest_packet`]): each node is fetched once for the packet and
//! its children tested against all the lanes at once. The camera rays of a pixel's samples,
//! and of neighbouring pixels, enter nearly the same nodes, so a packet costs about what one
//! of its rays costs alone (Wald, Slusallek, Benthin and Wagner, "Interactive Rendering with
//! Coherent Ray Tracing", Eurographics 2001).
//!
//! Every answer is the same bits as [`Scene::intersect`]'s: each lane tests the boxes and the
//! primitives it reaches by the single ray's operations (`Scene::keep_nearer`, the tie rule
//! included), and its hit becomes an [`Interaction`] by the same code, instances and masks
//! included.

use super::{Interaction, Scene, NO_HIT};
use crate::accel::{RayPacket, PACKET};

impl Scene {
    /// The closest hits of the lanes of `active` of `pk` into `out` by lane (the other lanes
    /// are left as they are): [`Scene::intersect`] of each lane's ray, the same bits, with
    /// the tree traversed once for all of them. The packet's `t_max` must be infinite, as
    /// `intersect`'s is.
    #[inline]
    pub fn intersect_packet(
        &self,
        pk: &RayPacket,
        active: u32,
        out: &mut [Option<Interaction>; PACKET],
    ) {
        self.intersect_packet_with(pk, active, PACKET, out);
    }

    /// [`Scene::intersect_packet`] with its box tests `lanes` (1, 8 or 16) rays at a time
    /// (16 only where the CPU has AVX-512, 8 only where it has AVX; see
    /// [`crate::accel::WideBvh::closest_packet_with`]).
    fn intersect_packet_with(
        &self,
        pk: &RayPacket,
        active: u32,
        lanes: usize,
        out: &mut [Option<Interaction>; PACKET],
    ) {
        debug_assert!(pk.t_max.iter().all(|&t| t == f32::INFINITY));
        let mut best = [NO_HIT; PACKET];
        let found = if self.is_flat() {
            // Brute force, faster than any tree for single rays, takes them one by one.
            let mut found = 0;
            for_lanes(active, |l| {
                if let Some(hit) = self.closest(&pk.ray(l), f32::INFINITY) {
                    (best[l], found) = (hit, found | 1 << l);
                }
            });
            found
        } else if self.masked {
            self.closest_lanes(pk, active, lanes, &mut best, |l, i, u, v, t| {
                self.seen(&pk.ray(l), i, u, v, t)
            })
        } else {
            self.closest_lanes(pk, active, lanes, &mut best, |_, _, _, _, _| true)
        };
        for_lanes(active, |l| {
            let hit = (found >> l & 1 != 0).then_some(best[l]);
            out[l] = self.interaction_of(&pk.ray(l), hit);
        });
    }

    /// `Scene::closest_kept` for the lanes of `active` of `pk` in one traversal: into `best`
    /// by lane, of the hits `keep` keeps (given the lane, primitive, u, v, t); returns the
    /// lanes with one.
    #[inline(always)]
    fn closest_lanes(
        &self,
        pk: &RayPacket,
        active: u32,
        lanes: usize,
        best: &mut [(usize, f32, f32, f32); PACKET],
        keep: impl Fn(usize, usize, f32, f32, f32) -> bool,
    ) -> u32 {
        self.bvh
            .closest_packet_with(pk, active, lanes, |i, lanes, t_max| {
                let mut nearer = 0;
                for_lanes(lanes, |l| {
                    let keep = |i, u, v, t| keep(l, i, u, v, t);
                    if let Some(t) = self.keep_nearer(&pk.ray(l), &mut best[l], i, t_max[l], &keep)
                    {
                        (t_max[l], nearer) = (t, nearer | 1 << l);
                    }
                });
                nearer
            })
    }
}

/// Calls `f` with each lane of `mask` (bit i: lane i), lowest first.
#[inline(always)]
fn for_lanes(mut mask: u32, mut f: impl FnMut(usize)) {
    while mask != 0 {
        f(mask.trailing_zeros() as usize);
        mask &= mask - 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::SingleRays;
    use crate::scene::desc::{GeometryDesc, SceneDesc, ShapeDesc};
    use glam::{Vec2, Vec3A};
    use std::path::Path;

    /// A scene file of the repository (`$file`, where a scene asks for one: an environment
    /// map).
    fn file(rel: &str) -> SceneDesc {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
        let opts = crate::LoadOptions {
            defines: vec![("file".into(), "sky.exr".into())],
            ..Default::default()
        };
        crate::load_scene_with(&path, &opts).unwrap_or_else(|e| panic!("{rel}: {e}"))
    }

    /// A number in [0, 1) from `k` (SplitMix64's finaliser).
    fn unit(k: u64) -> f32 {
        let mut z = k.wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Packets from the scene's camera position: each pixel's sixteen samples (coherent),
    /// rows of sixteen pixels, and sixteen directions over the sphere (any signs, some
    /// along an axis), with every lane active and with every other one. (A scene without a
    /// camera is seen from its centre, its "pixels" spread over the sphere.)
    fn packets(scene: &Scene) -> Vec<(RayPacket, u32)> {
        const RES: u32 = 12;
        let sphere = |s: f32, t: f32| {
            let (z, phi) = (1.0 - 2.0 * s, std::f32::consts::TAU * t);
            let r = (1.0 - z * z).max(0.0).sqrt();
            Vec3A::new(r * phi.cos(), r * phi.sin(), z)
        };
        type Pixel = Box<dyn Fn(u32, u32, Vec2) -> Vec3A>;
        let (o, pixel): (Vec3A, Pixel) = match scene.camera(None) {
            Some(cam) => {
                let cam = cam.build(RES, RES);
                let o = cam.generate_ray(0, 0, Vec2::splat(0.5)).o;
                (o, Box::new(move |x, y, u| cam.generate_ray(x, y, u).d))
            }
            None => {
                let b = scene.bounds().expect("a scene with something in it");
                let at = |x: u32, u: f32| (x as f32 + u) / RES as f32;
                (
                    (b.min + b.max) * 0.5,
                    Box::new(move |x, y, u| sphere(at(x, u.x), at(y, u.y))),
                )
            }
        };
        let packet = |d: &dyn Fn(usize) -> Vec3A| {
            let mut pk = RayPacket {
                o,
                d: [[0.0; PACKET]; 3],
                t_max: [f32::INFINITY; PACKET],
            };
            for l in 0..PACKET {
                let v = d(l);
                (pk.d[0][l], pk.d[1][l], pk.d[2][l]) = (v.x, v.y, v.z);
            }
            pk
        };
        let mut out = Vec::new();
        for y in 0..RES {
            for x in 0..RES {
                let k = u64::from(y * RES + x) << 8;
                let u = |l: usize| Vec2::new(unit(k + 2 * l as u64), unit(k + 2 * l as u64 + 1));
                out.push(packet(&|l| pixel(x, y, u(l))));
            }
            out.push(packet(&|l| {
                let x = (l as u32 * RES) / PACKET as u32;
                pixel(x, y, Vec2::splat(0.5))
            }));
            out.push(packet(&|l| {
                let k = (u64::from(y) << 16) + 2 * l as u64;
                match l {
                    0 => Vec3A::X,
                    1 => Vec3A::NEG_Z,
                    _ => sphere(unit(k), unit(k + 1)),
                }
            }));
        }
        out.into_iter()
            .flat_map(|pk| [(pk, u32::from(u16::MAX)), (pk, 0x5555)])
            .collect()
    }

    /// Checks every packet's answers, with each lane count, against `Scene::intersect`'s.
    fn check(scene: &Scene, what: &str) {
        if scene.bounds().is_none() {
            return; // (a file of BSDFs that others include: nothing to hit)
        }
        let packets = packets(scene);
        for lanes in [1, 8, 16] {
            for (pk, active) in &packets {
                let mut out = [None; PACKET];
                scene.intersect_packet_with(pk, *active, lanes, &mut out);
                for (l, got) in out.iter().enumerate() {
                    let want = (active >> l & 1 != 0)
                        .then(|| scene.intersect(&pk.ray(l)))
                        .flatten();
                    assert_eq!(
                        format!("{got:?}"),
                        format!("{want:?}"),
                        "{what}, {lanes} lanes, lane {l} of {pk:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn packets_hit_what_single_rays_hit() {
        let mut files: Vec<String> = std::fs::read_dir(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba/features"),
        )
        .expect("the feature scenes")
        .map(|e| e.expect("an entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "xml"))
        .map(|p| {
            format!(
                "tests/data/mitsuba/features/{}",
                p.file_name().unwrap().to_string_lossy()
            )
        })
        .collect();
        files.sort();
        files.push("tests/data/mitsuba/cornell-box.xml".into());
        files.push("tests/data/mitsuba/hexroom/hexroom.xml".into());
        for f in &files {
            for rays in [SingleRays::Auto, SingleRays::Bvh] {
                check(&Scene::build_with(file(f), rays), &format!("{f}, {rays:?}"));
            }
        }
    }

    /// The Cornell box with the Stanford bunny (3 674 triangles) in it, and two spheres.
    #[test]
    fn packets_hit_a_mesh_as_single_rays_do() {
        let mut desc = file("tests/data/mitsuba/cornell-box.xml");
        let bunny = crate::scene::obj::load_obj(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/data/bunny.obj"),
        )
        .expect("the bunny");
        let (lo, hi) = bunny.positions.iter().fold(
            (glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let scale = 0.6 / (hi - lo).max_element();
        let mut mesh = bunny;
        for p in &mut mesh.positions {
            *p = (*p - (lo + hi) * 0.5) * scale + glam::Vec3::new(0.0, 0.3, 0.0);
        }
        let shape = |geometry| ShapeDesc {
            geometry,
            material: 0,
            emission: None,
        };
        desc.shapes.push(shape(GeometryDesc::Mesh(mesh)));
        for (c, r) in [
            (glam::Vec3::new(0.5, 0.2, 0.3), 0.2),
            (glam::Vec3::new(-0.5, 0.8, 0.0), 0.1),
        ] {
            desc.shapes.push(shape(GeometryDesc::Sphere {
                center: c,
                radius: r,
            }));
        }
        check(&Scene::build(desc), "bunny box");
    }
}
