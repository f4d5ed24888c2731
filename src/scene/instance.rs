//! Instancing: shape groups stored once and placed any number of times (Mitsuba 3's
//! `shapegroup` and `instance` plugins; pbrt-v4's object instances).
//!
//! A two-level BVH. Each group is built as a scene of its own ([`Scene::build`]: its
//! primitives, in its object space, and their BVH), once, however many instances place it.
//! A top-level BVH over the instances' world bounds finds the instances a ray may hit; each
//! one's ray is taken into the group's object space by the inverse of its affine `to_world`
//! (origin and direction alike, the direction not renormalised, so a hit's parametric
//! distance is the same in both spaces and hits of different instances compare directly).
//! A hit is brought back as pbrt-v4's `TransformedPrimitive` does: the point by `to_world`,
//! with the rounding error of that transform added to its error bound (pbrt-v4 §6.8.6,
//! `Transform::operator()(Point3fi)`), normals by the inverse transpose (pbrt-v4 §3.10.3;
//! Mitsuba's `instance.cpp` the same). The bound also covers the error of taking a spawned
//! ray's origin back to object space, so that a ray leaving an instanced surface starts
//! beyond it in the group's space too (no self-intersection of shadow rays).
//!
//! Scenes without instances hold `None` and trace exactly as before.

use super::desc::{check_counts, shape_counts, GroupDesc};
use super::{Interaction, Scene, SceneDesc};
use crate::accel::bvh::{self, PrimRef};
use crate::accel::{BuildTimes, RayPacket, WideBvh};
use crate::geometry::ray::gamma;
use crate::geometry::{Aabb, Ray};
use glam::{Affine3A, Mat3A, Vec3A};

/// The instanced geometry of a scene.
pub struct Instances {
    groups: Vec<Group>,
    /// The instances, in the top-level BVH's order.
    placed: Vec<Placed>,
    /// Over the instances' world bounds.
    tlas: WideBvh,
}

/// A shape group, built once.
struct Group {
    name: String,
    /// Its shapes' primitives and BVH, in its object space, with the scene's materials (so
    /// its hits name them by the scene's indices).
    scene: Scene,
    /// Instances that place it.
    uses: usize,
}

/// One instance: the group and both ways between its object space and the world.
#[derive(Clone, Copy, Debug)]
struct Placed {
    to_object: Affine3A,
    to_world: Affine3A,
    group: u32,
}

/// The union of two optional boxes.
pub(crate) fn union(a: Option<Aabb>, b: Option<Aabb>) -> Option<Aabb> {
    match (a, b) {
        (Some(a), Some(b)) => Some(Aabb::union(&a, &b)),
        (a, b) => a.or(b),
    }
}

/// The instanced geometry of `desc` (whose groups and instances it takes), None without
/// instances. Groups that no instance places are dropped unbuilt.
pub(super) fn build(desc: &mut SceneDesc, times: &mut BuildTimes) -> Option<Box<Instances>> {
    let groups = std::mem::take(&mut desc.groups);
    let instances = std::mem::take(&mut desc.instances);
    if instances.is_empty() {
        return None;
    }
    let mut uses = vec![0usize; groups.len()];
    for i in &instances {
        uses[i.group as usize] += 1;
    }
    let groups: Vec<Group> = groups
        .into_iter()
        .zip(uses)
        .map(|(g, uses)| Group::build(g, uses, &desc.materials, &desc.textures))
        .collect();
    let placed: Vec<Placed> = instances
        .iter()
        .filter(|i| groups[i.group as usize].scene.bvh.bounds().is_some())
        .map(|i| Placed {
            to_object: i.to_world.inverse(),
            to_world: i.to_world,
            group: i.group,
        })
        .collect();
    let world: Vec<Aabb> = placed
        .iter()
        .map(|p| {
            world_bounds(
                &p.to_world,
                &groups[p.group as usize].scene.bvh.bounds().unwrap(),
            )
        })
        .collect();
    times.mark("shape groups");
    // Each instance costs a traversal of its group: never merged into a leaf with others.
    let mut tlas_times = BuildTimes::start();
    let (tlas, order) = bvh::build(
        placed.len(),
        |i| PrimRef::new(&world[i as usize], i, true),
        &mut tlas_times,
    );
    let placed = order.iter().map(|&i| placed[i as usize]).collect();
    times.mark("instances' BVH");
    Some(Box::new(Instances {
        groups,
        placed,
        tlas,
    }))
}

impl Group {
    fn build(
        g: GroupDesc,
        uses: usize,
        materials: &[crate::material::Material],
        textures: &[crate::texture::Texture],
    ) -> Group {
        if uses == 0 {
            return Group {
                name: g.name,
                scene: Scene::build(SceneDesc::default()),
                uses,
            };
        }
        // The group keeps the scene's material list and textures, so that material indices
        // (blends name their parts by index) and texture slots mean the same inside it
        // (materials are small; bitmaps are shared, not copied).
        let shapes = g.shapes;
        let materials = materials.to_vec();
        let desc = SceneDesc {
            materials,
            shapes,
            textures: textures.to_vec(),
            ..Default::default()
        };
        Group {
            name: g.name,
            scene: Scene::build(desc),
            uses,
        }
    }
}

/// The world bounds of a group's object-space `b` under `m`: the box of its eight corners,
/// widened by the rounding error of transforming a point (γ(3) of the magnitudes, pbrt-v4
/// §6.8.6), so that every transformed primitive lies inside.
fn world_bounds(m: &Affine3A, b: &Aabb) -> Aabb {
    let corners: Vec<Vec3A> = (0..8)
        .map(|k| {
            let pick = |bit: usize, lo: f32, hi: f32| if k & bit != 0 { hi } else { lo };
            m.transform_point3a(Vec3A::new(
                pick(1, b.min.x, b.max.x),
                pick(2, b.min.y, b.max.y),
                pick(4, b.min.z, b.max.z),
            ))
        })
        .collect();
    let w = Aabb::from_points(&corners);
    let pad = transform_error(m, b.min.abs().max(b.max.abs()));
    Aabb {
        min: w.min - pad,
        max: w.max + pad,
    }
}

/// The columns of `m` with their entries' magnitudes.
fn abs3(m: &Mat3A) -> Mat3A {
    Mat3A::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs())
}

/// Bound on the rounding error of `m` applied to a point of magnitudes `p_abs` (three
/// products and three sums per coordinate: γ(3) of |M||p| + |t|, pbrt-v4 §6.8.6).
fn transform_error(m: &Affine3A, p_abs: Vec3A) -> Vec3A {
    (abs3(&m.matrix3) * p_abs + m.translation.abs()) * gamma(3)
}

impl Placed {
    #[inline]
    fn ray_in_object_space(&self, ray: &Ray) -> Ray {
        Ray::new(
            self.to_object.transform_point3a(ray.o),
            self.to_object.transform_vector3a(ray.d),
        )
    }

    /// The shadow packet in object space (the shared origin stays shared).
    fn packet_in_object_space(&self, pk: &RayPacket) -> RayPacket {
        let m = self.to_object.matrix3;
        let mut out = *pk;
        out.o = self.to_object.transform_point3a(pk.o);
        for lane in 0..pk.t_max.len() {
            let d = m * Vec3A::new(pk.d[0][lane], pk.d[1][lane], pk.d[2][lane]);
            out.d[0][lane] = d.x;
            out.d[1][lane] = d.y;
            out.d[2][lane] = d.z;
        }
        out
    }

    /// An object-space hit in world space.
    fn hit_in_world(&self, si: Interaction) -> Interaction {
        let m = &self.to_world;
        let p = m.transform_point3a(si.p);
        // The object-space error carried through M (with M's own rounding of it), the error
        // of computing M p, and the error of computing M⁻¹ of a point near p (a spawned
        // ray's origin) taken back to the world by M.
        let abs_m = abs3(&m.matrix3);
        let p_err = abs_m * si.p_err * (1.0 + gamma(3))
            + transform_error(m, si.p.abs())
            + abs_m * transform_error(&self.to_object, p.abs() + abs_m * si.p_err);
        // Normals by the inverse transpose; the shading normal kept on the geometric
        // normal's side, unless a normal or bump map tilted it (in object space).
        let n = self.to_object.matrix3.transpose();
        let ng = (n * si.ng).normalize();
        let base = (n * si.ns_base).normalize();
        let base = if base.dot(ng) < 0.0 { -base } else { base };
        let ns = if si.ns == si.ns_base {
            base
        } else {
            (n * si.ns).normalize()
        };
        Interaction {
            p,
            p_err,
            ng,
            ns,
            ns_base: base,
            ..si
        }
    }
}

impl Instances {
    /// The closest hit along `ray`: an instance's nearer than `own` (the scene's own
    /// primitives' closest, [`Scene::closest`]), else `own`'s. (Not inlined, here and
    /// below: the callers' code stays as small as without instances.) Compiled for
    /// x86-64-v3 where the CPU has it, as `Scene::intersect_many` is, so that the trees' box
    /// tests take their eight-lane AVX form inline.
    #[inline(never)]
    pub(super) fn intersect(
        &self,
        scene: &Scene,
        ray: &Ray,
        own: Option<(usize, f32, f32, f32)>,
    ) -> Option<Interaction> {
        #[cfg(target_arch = "x86_64")]
        if crate::integrator::has_x86_64_v3() {
            // SAFETY: the CPU has the features, checked just above.
            return unsafe { self.intersect_v3(scene, ray, own) };
        }
        self.intersect_here(scene, ray, own)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn intersect_v3(
        &self,
        scene: &Scene,
        ray: &Ray,
        own: Option<(usize, f32, f32, f32)>,
    ) -> Option<Interaction> {
        self.intersect_here(scene, ray, own)
    }

    #[inline(always)]
    fn intersect_here(
        &self,
        scene: &Scene,
        ray: &Ray,
        own: Option<(usize, f32, f32, f32)>,
    ) -> Option<Interaction> {
        let t_own = own.map_or(f32::INFINITY, |h| h.3);
        match self.closest(ray, t_own) {
            Some(si) => Some(si),
            None => {
                let (i, u, v, t) = own?;
                Some(scene.interaction(ray, i, u, v, t))
            }
        }
    }

    /// The closest instance hit strictly before `t_max`.
    #[inline(always)]
    fn closest(&self, ray: &Ray, t_max: f32) -> Option<Interaction> {
        // (instance, primitive, u, v, t) of the nearest so far.
        let mut best: Option<(usize, usize, f32, f32, f32)> = None;
        self.tlas.intersect(
            ray,
            t_max,
            #[inline(always)]
            |k, t_max| {
                let (inst, group) = self.instance(k);
                let (i, u, v, t) = group.closest(&inst.ray_in_object_space(ray), t_max)?;
                (t < t_max).then(|| {
                    best = Some((k, i, u, v, t));
                    t
                })
            },
        );
        let (k, i, u, v, t) = best?;
        let (inst, group) = self.instance(k);
        let si = group.interaction(&inst.ray_in_object_space(ray), i, u, v, t);
        Some(inst.hit_in_world(si))
    }

    /// Instance `k` and its group's scene.
    #[inline(always)]
    fn instance(&self, k: usize) -> (&Placed, &Scene) {
        let inst = &self.placed[k];
        (inst, &self.groups[inst.group as usize].scene)
    }

    /// Whether an instance blocks `ray` before `t_max` (for x86-64-v3 where the CPU has it,
    /// as [`Instances::intersect`]).
    #[inline(never)]
    pub(super) fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        #[cfg(target_arch = "x86_64")]
        if crate::integrator::has_x86_64_v3() {
            // SAFETY: the CPU has the features, checked just above.
            return unsafe { self.occluded_v3(ray, t_max) };
        }
        self.occluded_here(ray, t_max)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn occluded_v3(&self, ray: &Ray, t_max: f32) -> bool {
        self.occluded_here(ray, t_max)
    }

    #[inline(always)]
    fn occluded_here(&self, ray: &Ray, t_max: f32) -> bool {
        self.tlas.occluded(
            ray,
            t_max,
            #[inline(always)]
            |k, t_max| {
                let (inst, group) = self.instance(k);
                group.occluded(&inst.ray_in_object_space(ray), t_max)
            },
        )
    }

    /// The lanes of `active` that an instance blocks, `lanes` rays at a time
    /// (`Scene::occluded_packet_with`).
    #[inline(never)]
    pub(super) fn occluded_packet_with(&self, pk: &RayPacket, active: u32, lanes: usize) -> u32 {
        self.tlas.occluded_packet_with(pk, active, lanes, |k, m| {
            let (inst, group) = self.instance(k);
            group.occluded_packet_with(&inst.packet_in_object_space(pk), m, lanes)
        })
    }

    /// The world bounds of all instances.
    pub(crate) fn bounds(&self) -> Option<Aabb> {
        self.tlas.bounds()
    }

    /// Primitives stored (each group's once).
    pub(super) fn stored_prims(&self) -> usize {
        self.groups.iter().map(|g| g.scene.prim_count()).sum()
    }

    pub(super) fn stored_triangles(&self) -> usize {
        self.groups.iter().map(|g| g.scene.triangle_count()).sum()
    }

    /// Primitives as rendered: each group's times its instances.
    pub fn effective_prims(&self) -> usize {
        self.groups
            .iter()
            .map(|g| g.scene.prim_count() * g.uses)
            .sum()
    }

    /// Bytes of the groups (each once, as [`Scene::memory_bytes`] counts a scene's own
    /// geometry).
    pub fn group_bytes(&self) -> usize {
        self.groups.iter().map(|g| g.scene.memory_bytes()).sum()
    }

    /// Bytes of the instances themselves: their transforms and the top-level BVH.
    pub fn instance_bytes(&self) -> usize {
        std::mem::size_of_val(&self.placed[..]) + self.tlas.memory_bytes()
    }

    pub fn memory_bytes(&self) -> usize {
        self.group_bytes() + self.instance_bytes()
    }

    /// The render summary's line: groups, instances and what they cost (`own_bytes`: the
    /// scene's geometry outside them).
    pub(super) fn summary(&self, own_bytes: usize) -> String {
        let built: Vec<&Group> = self.groups.iter().filter(|g| g.uses > 0).collect();
        let names: Vec<String> = built
            .iter()
            .take(4)
            .map(|g| {
                format!(
                    "'{}' {} primitives × {}",
                    g.name,
                    g.scene.prim_count(),
                    g.uses
                )
            })
            .collect();
        let more = if built.len() > 4 { ", …" } else { "" };
        let size = |b: usize| match b {
            0..1_000_000 => format!("{:.1} kB", b as f64 / 1e3),
            _ => format!("{:.2} MB", b as f64 / 1e6),
        };
        format!(
            "instancing: {} shape group(s) ({}{more}) stored once in {}; {} instances, \
             {:.0} bytes each (transforms and top-level BVH); {} primitives rendered; \
             geometry {} in all ({} outside instances)",
            built.len(),
            names.join(", "),
            size(self.group_bytes()),
            self.placed.len(),
            self.instance_bytes() as f64 / self.placed.len().max(1) as f64,
            self.effective_prims(),
            size(own_bytes + self.memory_bytes()),
            size(own_bytes),
        )
    }
}

/// What [`Scene::build`] cannot represent of the groups and instances: a group beyond the
/// limits of a scene, a group whose shapes emit (Mitsuba: "Instancing of emitters is not
/// supported"), more than [`crate::limits::MAX_INSTANCES`] instances, an instance of no
/// group, or one whose `to_world` is not finite and invertible.
pub(super) fn check_limits(desc: &SceneDesc) -> Result<(), String> {
    for g in &desc.groups {
        let (prims, vertices) = shape_counts(&g.shapes);
        check_counts(prims, vertices, desc.materials.len())
            .map_err(|e| format!("shape group '{}': {e}", g.name))?;
        if g.shapes.iter().any(|s| s.emission.is_some()) {
            return Err(format!(
                "shape group '{}': instancing of emitters is not supported",
                g.name
            ));
        }
        if g.shapes
            .iter()
            .any(|s| s.material as usize >= desc.materials.len())
        {
            return Err(format!("shape group '{}': a shape has no material", g.name));
        }
    }
    check_count(desc.instances.len())?;
    for i in &desc.instances {
        if i.group as usize >= desc.groups.len() {
            return Err(format!(
                "an instance refers to shape group {}, which does not exist",
                i.group
            ));
        }
        if let Some(why) = singular(&i.to_world) {
            return Err(format!(
                "an instance of shape group '{}' has a to_world that {why}",
                desc.groups[i.group as usize].name
            ));
        }
    }
    Ok(())
}

/// Refuses more than [`crate::limits::MAX_INSTANCES`] instances.
pub fn check_count(n: usize) -> Result<(), String> {
    crate::limits::check(
        "the number of instances",
        n as u64,
        0,
        crate::limits::MAX_INSTANCES,
    )
}

/// Why `m` cannot place an instance (not finite, or not invertible), if it cannot.
pub fn singular(m: &Affine3A) -> Option<&'static str> {
    if !m.is_finite() {
        return Some("is not finite");
    }
    let det = m.matrix3.determinant();
    if det == 0.0 || !det.is_finite() || !m.inverse().is_finite() {
        return Some("is singular (not invertible)");
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn instance_count_is_bounded() {
        let most = crate::limits::MAX_INSTANCES as usize;
        assert_eq!(check_count(most), Ok(()));
        assert!(check_count(most + 1).unwrap_err().contains("at most"));
    }

    #[test]
    fn singular_and_infinite_transforms_are_refused() {
        let ok = Affine3A::from_scale(glam::Vec3::new(1.0, 1e-3, 5.0));
        assert_eq!(singular(&ok), None);
        let flat = Affine3A::from_scale(glam::Vec3::new(1.0, 0.0, 5.0));
        assert!(singular(&flat).unwrap().contains("singular"));
        let inf = Affine3A::from_translation(glam::Vec3::new(f32::INFINITY, 0.0, 0.0));
        assert!(singular(&inf).unwrap().contains("finite"));
    }

    /// A description with an emitting group shape, an instance of a missing group or a
    /// singular instance is refused before the build.
    #[test]
    fn check_limits_refuses_what_the_build_cannot_trace() {
        use crate::scene::desc::{GeometryDesc, InstanceDesc, ShapeDesc};
        let mut desc = SceneDesc {
            materials: vec![crate::material::Material::new(
                crate::material::Bsdf::Lambert(crate::material::Lambert {
                    albedo: crate::Color::ONE,
                }),
                false,
            )],
            groups: vec![GroupDesc {
                name: "g".into(),
                shapes: vec![ShapeDesc {
                    geometry: GeometryDesc::Sphere {
                        center: glam::Vec3::ZERO,
                        radius: 1.0,
                    },
                    material: 0,
                    emission: None,
                }],
            }],
            instances: vec![InstanceDesc {
                group: 0,
                to_world: Affine3A::IDENTITY,
            }],
            ..Default::default()
        };
        assert_eq!(desc.check_limits(), Ok(()));
        desc.instances[0].group = 1;
        assert!(desc.check_limits().unwrap_err().contains("does not exist"));
        desc.instances[0].group = 0;
        desc.instances[0].to_world = Affine3A::from_scale(glam::Vec3::ZERO);
        assert!(desc.check_limits().unwrap_err().contains("singular"));
        desc.instances[0].to_world = Affine3A::IDENTITY;
        desc.groups[0].shapes[0].emission = Some(crate::Color::ONE);
        assert!(desc.check_limits().unwrap_err().contains("emitters"));
    }
}
