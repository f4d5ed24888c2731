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
use crate::simd::lanes_of;

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
    /// where the CPU allows (sixteen with AVX-512, eight with AVX; else one): the same
    /// answers each way, which the tests check by choosing.
    #[inline]
    pub fn intersect_packet_with(
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
            for l in lanes_of(active) {
                if let Some(hit) = self.closest(&pk.ray(l), f32::INFINITY) {
                    (best[l], found) = (hit, found | 1 << l);
                }
            }
            found
        } else if self.masked {
            self.closest_lanes(pk, active, lanes, &mut best, |l, i, u, v, t| {
                self.seen(&pk.ray(l), i, u, v, t)
            })
        } else {
            self.closest_lanes(pk, active, lanes, &mut best, |_, _, _, _, _| true)
        };
        for l in lanes_of(active) {
            let hit = (found >> l & 1 != 0).then_some(best[l]);
            self.interaction_into(&pk.ray(l), hit, &mut out[l]);
        }
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
                for l in lanes_of(lanes) {
                    let keep = |i, u, v, t| keep(l, i, u, v, t);
                    if let Some(t) = self.keep_nearer(&pk.ray(l), &mut best[l], i, t_max[l], &keep)
                    {
                        (t_max[l], nearer) = (t, nearer | 1 << l);
                    }
                }
                nearer
            })
    }
}
