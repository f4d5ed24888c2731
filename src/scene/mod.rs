//! Scenes: the description read from a file, and the built scene the integrators trace.
//!
//! Data flows one way: a file is parsed into a [`SceneDesc`] (geometry, materials, cameras and
//! settings, independent of the format), which [`Scene::build`] turns into primitives, a BVH,
//! materials and lights.

pub mod build;
pub mod cylinder;
pub mod desc;
pub mod error;
pub mod gltf;
pub mod instance;
pub mod mask;
pub mod obj;
mod packet;
mod perturb;
pub mod ply;
pub mod serialized;
pub mod stream;
pub mod text;
pub mod toml;
pub mod xml;

pub use desc::{GeometryDesc, GroupDesc, InstanceDesc, SceneDesc, ShapeDesc};
pub use error::SceneError;

use crate::accel::{RayPacket, WideBvh, PACKET};
use crate::camera::CameraDesc;
use crate::geometry::ray::{offset_ray_origin, SHADOW_EPSILON};
use crate::geometry::{Ray, Sphere, Triangle};
use crate::light::{Lights, NO_TEXTURE};
use crate::material::Material;
use glam::{Vec2, Vec3A, Vec4};

pub const NO_LIGHT: u32 = u32::MAX;

/// [`Scene::closest_kept`]'s nearest hit before it has one.
const NO_HIT: (usize, f32, f32, f32) = (usize::MAX, 0.0, 0.0, 0.0);

/// `Scene::tris` entry of a sphere: `[SPHERE, index into Scene::spheres, 0]`.
pub const SPHERE: u32 = u32::MAX;
/// `Scene::meta` flags: the primitive emits (its light is in `Scene::emitters`)...
pub const META_EMITTER: u32 = 1 << 31;
/// ...its mesh has vertex normals, or texture coordinates and a textured material (in
/// `Scene::attrs`).
pub const META_ATTRS: u32 = 1 << 30;
/// The material index is what remains.
pub const META_MATERIAL: u32 = (1 << 30) - 1;

/// Where a mesh's vertex normals and texture coordinates lie (meshes with either only).
#[derive(Clone, Copy, Debug)]
pub struct MeshAttrs {
    /// The mesh's first vertex in `Scene::positions`.
    pub first_vertex: u32,
    /// Its first vertex's normal in `Scene::normals`, or u32::MAX without normals.
    pub normals: u32,
    /// Its first vertex's texture coordinates in `Scene::uvs`, or u32::MAX without.
    pub uvs: u32,
    /// Its first vertex's tangent in `Scene::tangents`, or u32::MAX (without tangents, or
    /// without a normal map to read them).
    pub tangents: u32,
}

/// A ray's hit on a surface, with everything shading needs.
#[derive(Clone, Copy, Debug)]
pub struct Interaction {
    pub p: Vec3A,
    /// Conservative bound on the floating-point error of `p`, per axis.
    pub p_err: Vec3A,
    /// Unit geometric normal, oriented as the geometry defines it (front side).
    pub ng: Vec3A,
    /// Unit shading normal, on the same side as `ng` (a normal or bump map may tilt it
    /// beyond; see [`crate::material::normal_map`]).
    pub ns: Vec3A,
    /// The shading normal before a normal or bump map perturbed `ns`; `ns` elsewhere.
    pub ns_base: Vec3A,
    pub t: f32,
    /// Texture coordinates: the mesh's, interpolated, under a texture; barycentric (b1, b2)
    /// on a mesh without them or without a texture to read them; (φ/2π, θ/π) on a textured
    /// sphere (Mitsuba's conventions), zero on others.
    pub uv: Vec2,
    pub material: u32,
    pub light: u32,
}

impl Interaction {
    /// A ray leaving this point in direction `d`, offset off the surface to `d`'s side.
    #[inline]
    pub fn spawn_ray(&self, d: Vec3A) -> Ray {
        Ray::new(offset_ray_origin(self.p, self.p_err, self.ng, d), d)
    }

    /// The shadow ray towards a light sample, and the parametric distance up to which it
    /// must be unobstructed (to infinity for a light at infinity).
    #[inline(always)]
    pub fn spawn_ray_to_light(&self, ls: &crate::light::LightSample) -> (Ray, f32) {
        if ls.infinite {
            (self.spawn_ray(ls.wi), f32::INFINITY)
        } else {
            self.spawn_ray_to(ls.p, ls.p_err, ls.n)
        }
    }

    /// A shadow ray from this point to the point `p2` (normal `n2`, error `err2`); returns
    /// the ray and the parametric distance up to which it must be unobstructed.
    #[inline(always)]
    pub fn spawn_ray_to(&self, p2: Vec3A, err2: Vec3A, n2: Vec3A) -> (Ray, f32) {
        let d0 = p2 - self.p;
        let o = offset_ray_origin(self.p, self.p_err, self.ng, d0);
        let target = offset_ray_origin(p2, err2, n2, o - p2);
        (Ray::new(o, target - o), 1.0 - SHADOW_EPSILON)
    }
}

/// A sphere's frame: its rotation from the world into its local axes, where its texture
/// coordinates are measured (None: the world's), and whether its normals point inwards
/// (Mitsuba's `flip_normals`).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SphereFrame {
    pub(crate) to_local: Option<glam::Mat3A>,
    pub(crate) flip: bool,
}

impl SphereFrame {
    /// A world direction in the sphere's local axes.
    #[inline]
    pub(crate) fn local(&self, d: Vec3A) -> Vec3A {
        self.to_local.map_or(d, |m| m * d)
    }

    /// A local direction in world axes.
    #[inline]
    pub(crate) fn world(&self, d: Vec3A) -> Vec3A {
        self.to_local.map_or(d, |m| m.transpose() * d)
    }
}

pub struct Scene {
    /// Per primitive, in BVH order: a triangle's three indices into `positions`, or
    /// `[SPHERE, index into spheres, 0]`.
    pub(crate) tris: Vec<[u32; 3]>,
    /// Per primitive, in BVH order: material index and the META_* flags.
    pub(crate) meta: Vec<u32>,
    /// Vertex positions of all meshes, one after the other, and one padding vertex.
    pub(crate) positions: Vec<glam::Vec3>,
    pub(crate) spheres: Vec<Sphere>,
    /// Per sphere (as `spheres`), its own frame and orientation.
    pub(crate) sphere_frames: Vec<SphereFrame>,
    /// (primitive, area light) of each emitting primitive, by primitive.
    pub(crate) emitters: Vec<(u32, u32)>,
    /// Vertex normals and texture coordinates of the meshes that have them (a triangle's face
    /// normal and barycentric uvs stand in for what its mesh lacks), located by `attrs`,
    /// sorted by first vertex.
    pub(crate) normals: Vec<glam::Vec3>,
    pub(crate) uvs: Vec<Vec2>,
    /// Vertex tangents (xyz, bitangent sign w) of normal-mapped meshes that have them.
    pub(crate) tangents: Vec<Vec4>,
    pub(crate) attrs: Vec<MeshAttrs>,
    pub bvh: WideBvh,
    /// The primitives of a small scene for brute-force tests of single rays, where the CPU
    /// has AVX (see [`crate::accel::flat`]); the packets keep to the BVH.
    #[cfg(target_arch = "x86_64")]
    pub(crate) flat: Option<Box<crate::accel::flat::Flat>>,
    pub materials: Vec<Material>,
    pub lights: Lights,
    pub textures: Vec<crate::texture::Texture>,
    pub cameras: Vec<(String, CameraDesc)>,
    pub desc_settings: desc::FileSettings,
    /// Whether a material has an opacity (`mask`): rays then pass its surfaces by chance
    /// ([`mask`]).
    pub(crate) masked: bool,
    /// How long each phase of `Scene::build` took.
    pub build_times: crate::accel::BuildTimes,
    /// Shape groups, each stored once, and their instances (None without any).
    pub(crate) instances: Option<Box<instance::Instances>>,
}

impl Scene {
    #[inline(always)]
    fn vertex(&self, i: u32) -> Vec3A {
        Vec3A::from(self.positions[i as usize])
    }

    #[inline(always)]
    pub(crate) fn triangle(&self, [a, b, c]: [u32; 3]) -> Triangle {
        Triangle::new(self.vertex(a), self.vertex(b), self.vertex(c))
    }

    /// Vertex `i` by one unaligned 16-byte load (its fourth lane is the next vertex's x,
    /// which no Vec3A operation reads), for the intersection tests.
    #[inline(always)]
    fn vertex_fast(&self, i: u32) -> Vec3A {
        debug_assert!((i as usize) + 1 < self.positions.len());
        // SAFETY: `positions` ends with a padding vertex and every index in `tris` is below
        // its last (checked by `Scene::build`, the only writer of both), so the 16 bytes from
        // vertex i lie inside the array.
        unsafe {
            let p = self.positions.as_ptr().add(i as usize) as *const f32;
            #[cfg(target_arch = "x86_64")]
            {
                Vec3A::from(std::arch::x86_64::_mm_loadu_ps(p))
            }
            #[cfg(not(target_arch = "x86_64"))]
            {
                Vec3A::new(*p, *p.add(1), *p.add(2))
            }
        }
    }

    /// Primitive `i` (BVH order) hit before `t_max`: (t, u, v) (spheres: (t, 0, 0)).
    #[inline(always)]
    pub(crate) fn hit(&self, ray: &Ray, i: usize, t_max: f32) -> Option<(f32, f32, f32)> {
        debug_assert!(i < self.tris.len());
        // SAFETY: the BVH's leaves name primitives below tris.len() (Scene::build).
        let [a, b, c] = unsafe { *self.tris.get_unchecked(i) };
        if a != SPHERE {
            Triangle::new(
                self.vertex_fast(a),
                self.vertex_fast(b),
                self.vertex_fast(c),
            )
            .intersect(ray, t_max)
        } else {
            self.spheres[b as usize]
                .intersect(ray, t_max)
                .map(|t| (t, 0.0, 0.0))
        }
    }

    /// Whether primitive `i` blocks `ray` before `t_max` where it is seen (through its
    /// mask), the occlusion test of a scene with masks.
    #[inline(always)]
    pub(crate) fn blocks_seen(&self, ray: &Ray, i: usize, t_max: f32) -> bool {
        self.hit(ray, i, t_max)
            .is_some_and(|(t, u, v)| self.seen(ray, i, u, v, t))
    }

    /// Closest hit along the ray, if any.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray) -> Option<Interaction> {
        self.interaction_of(ray, self.closest(ray, f32::INFINITY))
    }

    /// [`Scene::intersect`]'s answer from the closest of the scene's own primitives (as
    /// [`Scene::closest`] gives it).
    #[inline(always)]
    fn interaction_of(
        &self,
        ray: &Ray,
        hit: Option<(usize, f32, f32, f32)>,
    ) -> Option<Interaction> {
        let mut out = None;
        self.interaction_into(ray, hit, &mut out);
        out
    }

    /// [`Scene::interaction_of`] written into `out`. The batches' queries write each answer
    /// in place: built on the stack and copied out, an interaction was stored in 16-byte
    /// pieces and loaded back in 32-byte ones, which the CPU cannot forward from the stores
    /// (on the bunny box, two fifths of `intersect_many`'s own time waited on those copies).
    #[inline(always)]
    fn interaction_into(
        &self,
        ray: &Ray,
        hit: Option<(usize, f32, f32, f32)>,
        out: &mut Option<Interaction>,
    ) {
        if let Some(inst) = &self.instances {
            *out = inst.intersect(self, ray, hit);
            return;
        }
        match hit {
            Some((i, u, v, t)) => self.interaction_in(ray, i, u, v, t, out),
            None => *out = None,
        }
    }

    /// Closest hits of several rays: `out[k]` is [`Scene::intersect`]`(&rays[k])`, the same
    /// bits, for the stream path tracer, which traces a batch of independent rays at once so
    /// that their memory loads can overlap (see [`stream`]; one by one where the scene fits
    /// in the cache, [`Scene::streams`]). Panics if the slices' lengths differ.
    pub fn intersect_many(&self, rays: &[Ray], out: &mut [Option<Interaction>]) {
        #[cfg(target_arch = "x86_64")]
        if crate::integrator::has_x86_64_v3() {
            // SAFETY: the CPU has the features, checked just above.
            return unsafe { self.intersect_many_v3(rays, out) };
        }
        self.intersect_many_portable(rays, out);
    }

    /// [`Scene::intersect_many`] compiled for x86-64-v3, as the stream's path that calls it
    /// is (`integrator::stream::render_tile_v3`; a function's features do not pass to the
    /// functions it calls): in its SSE2 form it took 6 % more instructions on the bunny box.
    /// Rust does not fuse multiplies and adds, so the answers are the same bits. Rays one by
    /// one go through [`Scene::closest_v3`].
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn intersect_many_v3(&self, rays: &[Ray], out: &mut [Option<Interaction>]) {
        if self.intersect_many_flat(rays, out) {
            return;
        }
        if self.streams() {
            self.intersect_many_k::<{ stream::STREAM }>(rays, out);
            return;
        }
        assert_eq!(rays.len(), out.len(), "one output per ray");
        for (ray, o) in rays.iter().zip(out.iter_mut()) {
            self.interaction_into(ray, self.closest_v3(ray), o);
        }
    }

    /// [`Scene::closest`] up to infinity, compiled for x86-64-v3 in a function of its own:
    /// inlined into the loop over the rays, the traversal shared the registers with the
    /// interaction's code and reloaded the ray's slab operands and the node's slab offsets
    /// from the stack at every node (ten loads a node more).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
    #[inline(never)]
    unsafe fn closest_v3(&self, ray: &Ray) -> Option<(usize, f32, f32, f32)> {
        self.closest(ray, f32::INFINITY)
    }

    #[inline(always)]
    fn intersect_many_portable(&self, rays: &[Ray], out: &mut [Option<Interaction>]) {
        if self.intersect_many_flat(rays, out) {
            return;
        }
        if self.streams() {
            self.intersect_many_k::<{ stream::STREAM }>(rays, out);
        } else {
            self.intersect_many_k::<1>(rays, out);
        }
    }

    /// The closest of this scene's own primitives (not its instances) hit before `t_max`
    /// (or at it), and seen (through masks): (primitive, u, v, t).
    #[inline(always)]
    fn closest(&self, ray: &Ray, t_max: f32) -> Option<(usize, f32, f32, f32)> {
        if self.masked {
            return self.closest_kept(ray, t_max, |i, u, v, t| self.seen(ray, i, u, v, t));
        }
        #[cfg(target_arch = "x86_64")]
        if let Some(f) = &self.flat {
            let (i, t, u, v) = f.intersect(
                ray,
                t_max,
                #[inline(always)]
                |i, t_max| self.hit(ray, i, t_max),
            )?;
            return Some((i, u, v, t));
        }
        self.closest_kept(ray, t_max, |_, _, _, _| true)
    }

    /// [`Scene::closest`] through the BVH, of the hits `keep` keeps (given the primitive,
    /// u, v, t).
    #[inline(always)]
    fn closest_kept(
        &self,
        ray: &Ray,
        t_max: f32,
        keep: impl Fn(usize, f32, f32, f32) -> bool,
    ) -> Option<(usize, f32, f32, f32)> {
        // Of equally near hits the lowest primitive, whatever the order the traversal
        // visits them in (as `accel::flat` finds them; see `keep_nearer`).
        let mut best = NO_HIT;
        let found = self.bvh.intersect(
            ray,
            t_max,
            #[inline(always)]
            |i, t_max| self.keep_nearer(ray, &mut best, i, t_max, &keep),
        );
        found.then_some(best)
    }

    /// The distance of primitive `i`'s hit by `ray` if `keep` keeps it and it is nearer than
    /// `t_max` or as near and lower than `best`'s primitive; `best` then becomes it
    /// (primitive, u, v, t). The primitive is tested without a bound (its tests read `t_max`
    /// only to accept their answer), so the rule holds in any order of visits.
    #[inline(always)]
    fn keep_nearer(
        &self,
        ray: &Ray,
        best: &mut (usize, f32, f32, f32),
        i: usize,
        t_max: f32,
        keep: &impl Fn(usize, f32, f32, f32) -> bool,
    ) -> Option<f32> {
        take_nearer(best, i, self.hit(ray, i, f32::INFINITY)?, t_max, keep)
    }

    #[inline(always)]
    fn interaction(&self, ray: &Ray, i: usize, u: f32, v: f32, t_hit: f32) -> Interaction {
        let mut out = None;
        self.interaction_in(ray, i, u, v, t_hit, &mut out);
        out.expect("interaction_in writes an interaction")
    }

    /// The interaction at the hit of `ray` on primitive `i` (u, v, t), written into `out`
    /// (see [`Scene::interaction_into`]).
    #[inline(always)]
    fn interaction_in(
        &self,
        ray: &Ray,
        i: usize,
        u: f32,
        v: f32,
        t_hit: f32,
        out: &mut Option<Interaction>,
    ) {
        let idx = self.tris[i];
        let meta = self.meta[i];
        let material = meta & META_MATERIAL;
        let light = if meta & META_EMITTER != 0 {
            self.emitter_light(i)
        } else {
            NO_LIGHT
        };
        if idx[0] != SPHERE {
            let tri = self.triangle(idx);
            let (p, p_err) = tri.point(u, v);
            let ng = tri.normal_unnormalized().normalize();
            let (mut ns, mut uv) = (ng, Vec2::new(u, v));
            let mut uv3 = None;
            let mut tangent = None;
            if meta & META_ATTRS != 0 {
                let m = self.mesh_attrs(idx[0]);
                let local = idx.map(|k| (k - m.first_vertex) as usize);
                if m.normals != u32::MAX {
                    let ns3 = &self.normals[m.normals as usize..];
                    let [n0, n1, n2] = local.map(|k| Vec3A::from(ns3[k]));
                    let n = (n0 * (1.0 - u - v) + n1 * u + n2 * v).normalize_or_zero();
                    // Keep the shading normal on the geometric normal's side.
                    ns = if n == Vec3A::ZERO {
                        ng
                    } else if n.dot(ng) < 0.0 {
                        -n
                    } else {
                        n
                    };
                }
                if m.uvs != u32::MAX {
                    let uvs = &self.uvs[m.uvs as usize..];
                    let [t0, t1, t2] = local.map(|k| uvs[k]);
                    uv = t0 * (1.0 - u - v) + t1 * u + t2 * v;
                    uv3 = Some([t0, t1, t2]);
                }
                if m.tangents != u32::MAX {
                    let ts = &self.tangents[m.tangents as usize..];
                    let [t0, t1, t2] = local.map(|k| ts[k]);
                    tangent = Some(t0 * (1.0 - u - v) + t1 * u + t2 * v);
                }
            }
            let si = out.insert(Interaction {
                p,
                p_err,
                ng,
                ns,
                ns_base: ns,
                t: t_hit,
                uv,
                material,
                light,
            });
            if meta & META_ATTRS != 0 && self.materials[material as usize].perturbs() {
                *si = self.perturb_triangle(*si, ray, &tri, uv3, tangent);
            }
        } else {
            let s = &self.spheres[idx[1] as usize];
            let frame = &self.sphere_frames[idx[1] as usize];
            let (p, n, p_err) = s.surface_point(ray.at(t_hit));
            // The angles only where a texture reads them (an arctangent and an arccosine),
            // in the sphere's own frame (Mitsuba's sphere.cpp).
            let mat = &self.materials[material as usize];
            let uv = if mat.reads_uv()
                || (light != NO_LIGHT && self.lights.lights[light as usize].texture != NO_TEXTURE)
            {
                sphere_uv(frame.local(n))
            } else {
                Vec2::ZERO
            };
            let n = if frame.flip { -n } else { n };
            let si = out.insert(Interaction {
                p,
                p_err,
                ng: n,
                ns: n,
                ns_base: n,
                t: t_hit,
                uv,
                material,
                light,
            });
            if mat.perturbs() {
                *si = self.perturb_sphere(*si, ray, s.radius, frame);
            }
        }
    }

    /// The area light of emitting primitive `i`.
    #[cold]
    fn emitter_light(&self, i: usize) -> u32 {
        let k = self.emitters.partition_point(|&(p, _)| (p as usize) < i);
        self.emitters[k].1
    }

    /// The attributes of the mesh holding vertex `v`.
    fn mesh_attrs(&self, v: u32) -> &MeshAttrs {
        let k = self.attrs.partition_point(|m| m.first_vertex <= v);
        &self.attrs[k - 1]
    }

    /// True if anything blocks the ray before parametric distance `t_max`.
    #[inline(always)]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.occluded_prims(ray, t_max)
            || (self.instances.as_ref()).is_some_and(|inst| inst.occluded(ray, t_max))
    }

    /// [`Scene::occluded`] by this scene's own primitives (not its instances).
    #[inline(always)]
    fn occluded_prims(&self, ray: &Ray, t_max: f32) -> bool {
        if self.masked {
            return self
                .bvh
                .occluded(ray, t_max, |i, t_max| self.blocks_seen(ray, i, t_max));
        }
        #[cfg(target_arch = "x86_64")]
        if let Some(f) = &self.flat {
            return f.occluded(
                ray,
                t_max,
                #[inline(always)]
                |i, t_max| self.hit(ray, i, t_max),
            );
        }
        self.bvh.occluded(
            ray,
            t_max,
            #[inline(always)]
            |i, t_max| self.hit(ray, i, t_max).is_some(),
        )
    }

    /// The lanes of `active` whose rays are blocked before their `t_max`: the answers of
    /// [`Scene::occluded`] for each, in one traversal.
    #[inline]
    pub fn occluded_packet(&self, pk: &RayPacket, active: u32) -> u32 {
        self.occluded_packet_with(pk, active, PACKET)
    }

    /// [`Scene::occluded_packet`] with its box tests `lanes` (1, 8 or 16) rays at a time
    /// where the CPU allows (sixteen with AVX-512, eight with AVX; else one): the same
    /// answers each way, which the tests check by choosing.
    #[inline]
    pub fn occluded_packet_with(&self, pk: &RayPacket, active: u32, lanes: usize) -> u32 {
        let width = packet::triangle_lanes(lanes);
        let hits = self.bvh.occluded_packet_with(pk, active, lanes, |i, m| {
            self.packet_hits(pk, None, i, m, width)
        });
        match &self.instances {
            Some(inst) if hits != active => {
                hits | inst.occluded_packet_with(pk, active & !hits, lanes)
            }
            _ => hits,
        }
    }

    /// Occlusion of rays that start near one another and head the same way, as the shadow
    /// rays of a pixel's samples from their first vertices do: `out[k]` is
    /// [`Scene::occluded`]`(&rays[k], t_max[k])`, sixteen consecutive rays traced as one
    /// packet of their own origins (`WideBvh::occluded_origins`). Panics if the slices'
    /// lengths differ.
    pub fn occluded_origins(&self, rays: &[Ray], t_max: &[f32], out: &mut [bool]) {
        self.occluded_origins_with(rays, t_max, PACKET, out);
    }

    /// [`Scene::occluded_origins`] with its box tests `lanes` (1, 8 or 16) rays at a time
    /// where the CPU allows: the same answers each way, which the tests check by choosing.
    pub fn occluded_origins_with(
        &self,
        rays: &[Ray],
        t_max: &[f32],
        lanes: usize,
        out: &mut [bool],
    ) {
        assert!(rays.len() == t_max.len() && rays.len() == out.len());
        let packets = rays.chunks(PACKET).zip(t_max.chunks(PACKET));
        for ((rays, t_max), out) in packets.zip(out.chunks_mut(PACKET)) {
            let hits = self.occluded_packet_of_origins(rays, t_max, lanes);
            for (l, o) in out.iter_mut().enumerate() {
                *o = hits >> l & 1 != 0;
            }
        }
    }

    /// Bit k set where `rays[k]` (at most [`PACKET`] of them) is blocked before `t_max[k]`.
    #[inline(always)]
    fn occluded_packet_of_origins(&self, rays: &[Ray], t_max: &[f32], lanes: usize) -> u32 {
        let all = (1u32 << rays.len()) - 1;
        let hits = if self.is_flat() {
            // Brute force takes its rays one by one (as `intersect_packet_with`).
            (0..rays.len()).fold(0, |m, k| {
                m | (self.occluded_prims(&rays[k], t_max[k]) as u32) << k
            })
        } else {
            let mut o = [[0.0; PACKET]; 3];
            let mut pk = RayPacket {
                o: Vec3A::ZERO,
                d: [[0.0; PACKET]; 3],
                t_max: [0.0; PACKET],
            };
            for (k, r) in rays.iter().enumerate() {
                (o[0][k], o[1][k], o[2][k]) = (r.o.x, r.o.y, r.o.z);
                (pk.d[0][k], pk.d[1][k], pk.d[2][k]) = (r.d.x, r.d.y, r.d.z);
                pk.t_max[k] = t_max[k];
            }
            let width = packet::triangle_lanes(lanes);
            self.bvh.occluded_origins(&o, &pk, all, lanes, |i, m| {
                self.packet_hits(&pk, Some(&o), i, m, width)
            })
        };
        match &self.instances {
            Some(inst) if hits != all => crate::simd::lanes_of(all & !hits).fold(hits, |m, k| {
                m | (inst.occluded(&rays[k], t_max[k]) as u32) << k
            }),
            _ => hits,
        }
    }

    /// Bytes held by the geometry the integrators trace: per-primitive indices and
    /// materials, vertex positions, normals and texture coordinates, spheres, the emitter
    /// table and BVH nodes (not materials, textures or lights); with instances, each
    /// group's once and the instances' own ([`instance::Instances::memory_bytes`]).
    pub fn memory_bytes(&self) -> usize {
        self.own_memory_bytes() + self.instances.as_ref().map_or(0, |i| i.memory_bytes())
    }

    /// [`Scene::memory_bytes`] of this scene's own primitives (not its instances).
    fn own_memory_bytes(&self) -> usize {
        use std::mem::size_of_val;
        size_of_val(&self.tris[..])
            + size_of_val(&self.meta[..])
            + size_of_val(&self.positions[..])
            + size_of_val(&self.spheres[..])
            + size_of_val(&self.sphere_frames[..])
            + size_of_val(&self.emitters[..])
            + size_of_val(&self.normals[..])
            + size_of_val(&self.uvs[..])
            + size_of_val(&self.tangents[..])
            + size_of_val(&self.attrs[..])
            + self.bvh.memory_bytes()
            + self.flat_bytes()
    }

    fn flat_bytes(&self) -> usize {
        #[cfg(target_arch = "x86_64")]
        if let Some(f) = &self.flat {
            return f.memory_bytes();
        }
        0
    }

    /// Whether single rays are traced by brute force ([`crate::accel::flat`]) rather than
    /// through the BVH ([`crate::accel::SingleRays`], chosen when the scene is built).
    pub fn is_flat(&self) -> bool {
        #[cfg(target_arch = "x86_64")]
        return self.flat.is_some();
        #[cfg(not(target_arch = "x86_64"))]
        false
    }

    /// The material at a hit: its textured parameters evaluated there, a blend resolved
    /// ([`Material::at`]).
    #[inline]
    pub fn material_at(&self, si: &Interaction) -> Material {
        let m = &self.materials[si.material as usize];
        let perturbed = m
            .perturbs()
            .then(|| crate::material::normal_map::Perturbed::new(si.ns, si.ns_base));
        m.at(&self.materials, &self.textures, si.uv, perturbed)
    }

    /// The mesh texture coordinates of triangle `idx`'s vertices, if its mesh has them
    /// (kept for primitives flagged META_ATTRS only).
    fn vertex_uvs(&self, idx: [u32; 3]) -> Option<[Vec2; 3]> {
        let m = self.mesh_attrs(idx[0]);
        (m.uvs != u32::MAX).then(|| {
            let uvs = &self.uvs[m.uvs as usize..];
            idx.map(|k| uvs[(k - m.first_vertex) as usize])
        })
    }

    pub fn camera(&self, name: Option<&str>) -> Option<&CameraDesc> {
        match name {
            None => self.cameras.first().map(|(_, c)| c),
            Some(n) => self.cameras.iter().find(|(k, _)| k == n).map(|(_, c)| c),
        }
    }

    /// Primitives stored: triangles and spheres, each group's once (however many
    /// instances place it).
    pub fn prim_count(&self) -> usize {
        self.tris.len() + self.instances.as_ref().map_or(0, |i| i.stored_prims())
    }

    /// Triangles stored, each group's once.
    pub fn triangle_count(&self) -> usize {
        self.tris.len() - self.spheres.len()
            + self.instances.as_ref().map_or(0, |i| i.stored_triangles())
    }

    /// The bounds of everything the scene holds, instances included (None if empty).
    pub fn bounds(&self) -> Option<crate::geometry::Aabb> {
        instance::union(
            self.bvh.bounds(),
            self.instances.as_ref().and_then(|i| i.bounds()),
        )
    }

    /// A line on the scene's instancing for the render summary (None without instances).
    pub fn instancing_summary(&self) -> Option<String> {
        self.instances
            .as_ref()
            .map(|i| i.summary(self.own_memory_bytes()))
    }
}

/// Texture coordinates on a sphere at unit normal `n` (Mitsuba's): (φ/2π, θ/π).
/// [`Scene::keep_nearer`]'s rule for primitive `i`'s hit (t, u, v), found without a bound:
/// it becomes `best` (primitive, u, v, t), and its distance is returned, if `keep` keeps it
/// and it is nearer than `t_max`, or as near and of a lower primitive than `best`'s.
#[inline(always)]
fn take_nearer(
    best: &mut (usize, f32, f32, f32),
    i: usize,
    (t, u, v): (f32, f32, f32),
    t_max: f32,
    keep: &impl Fn(usize, f32, f32, f32) -> bool,
) -> Option<f32> {
    ((t < t_max || (t == t_max && i < best.0)) && keep(i, u, v, t)).then(|| {
        *best = (i, u, v, t);
        t
    })
}

pub(crate) use crate::geometry::sphere::uv_of_normal as sphere_uv;
