//! The closest-hit traversal as a step function, and several rays traversed together, a
//! step each in turn, each prefetching what its next step reads.
//!
//! A ray through a tree larger than the caches waits on each node's load before it knows the
//! next: its traversal is a chain of dependent cache misses, and one ray has nothing to do
//! meanwhile (prefetching a single ray's children did not pay). Rays that are independent of
//! each other have independent chains. [`WideBvh::intersect_stream`] keeps up to `K` of them
//! in flight: each takes one step (one wide node's box test, or one leaf's primitives), asks
//! the CPU for the memory its next step will read (`prefetch`), and hands over to the next
//! ray, so that by its next turn the lines have arrived while the other rays computed. This is
//! Kocberber et al.'s asynchronous memory access chaining ("AMAC", VLDB 2015) applied to BVH
//! traversal; Embree's stream mode and Mitsuba's wavefront variants get their speed from many
//! rays in flight too.
//!
//! Each ray's decisions are those of [`WideBvh::intersect`] by construction: both repeat
//! the one step `closest_step!` (in `accel/wide.rs`), here on a [`Closest`], which holds all
//! of a ray's state; the interleaving changes only when its steps run, never what they
//! compute.

use super::{ChildRef, Node4, RayBoxes, Stack, WideBvh, EMPTY, LEAF, WIDEN};
use crate::accel::prefetch;
use crate::geometry::Ray;
use std::mem::MaybeUninit;

/// One ray's closest-hit traversal between steps: its prepared ray, the postponed children
/// with their entry distances, the node or leaf its next step visits, the distance of the
/// nearest hit so far and whether there is one.
pub(crate) struct Closest {
    r: RayBoxes,
    stack: Stack<(u32, f32)>,
    cur: ChildRef,
    pub(crate) t_max: f32,
    pub(crate) found: bool,
}

impl Closest {
    /// Starts the traversal of `ray` up to `t_max` in `slot` (left uninitialised until now:
    /// only the stack's length is written, not its items) at the root of `bvh`, which must
    /// not be `EMPTY`.
    #[inline(always)]
    pub(crate) fn start<'a>(
        slot: &'a mut MaybeUninit<Closest>,
        bvh: &WideBvh,
        ray: &Ray,
        t_max: f32,
    ) -> &'a mut Closest {
        debug_assert!(bvh.root != EMPTY);
        let p = slot.as_mut_ptr();
        // SAFETY: every field but the stack's items is written here, and those are
        // MaybeUninit, read only below the length set to 0 (see `Stack`).
        unsafe {
            std::ptr::addr_of_mut!((*p).r).write(RayBoxes::new(ray));
            std::ptr::addr_of_mut!((*p).stack.len).write(0);
            std::ptr::addr_of_mut!((*p).cur).write(bvh.root);
            std::ptr::addr_of_mut!((*p).t_max).write(t_max);
            std::ptr::addr_of_mut!((*p).found).write(false);
            slot.assume_init_mut()
        }
    }

    /// One step: the box test of the current node's children (the nearest entered is next,
    /// the others postponed, farthest first), or the tests of the current leaf's primitives
    /// by `hit` (see [`WideBvh::intersect`]); then, where no child was entered, the next
    /// postponed child that the ray still enters before its nearest hit. False when none is
    /// left: the traversal is over.
    #[inline(always)]
    pub(crate) fn step<F: FnMut(usize, f32) -> Option<f32>>(
        &mut self,
        bvh: &WideBvh,
        hit: &mut F,
    ) -> bool {
        closest_step!(
            bvh,
            self.r,
            self.stack,
            self.cur,
            self.t_max,
            self.found,
            hit,
            { return true },
            { return false }
        )
    }
}

/// A ray in flight in [`WideBvh::intersect_stream`]: its traversal, its index in the batch,
/// and the caller's state for it.
struct Slot<S> {
    c: Closest,
    k: usize,
    s: S,
}

impl<S: Copy> Slot<S> {
    /// Starts ray `k` in `slot` (see [`Closest::start`]).
    #[inline(always)]
    fn start(
        slot: &mut MaybeUninit<Slot<S>>,
        bvh: &WideBvh,
        ray: &Ray,
        t_max: f32,
        k: usize,
        s: S,
    ) {
        let p = slot.as_mut_ptr();
        // SAFETY: `c` is started in place (MaybeUninit has the layout of what it wraps), `k`
        // and `s` are written: the whole slot is initialised.
        unsafe {
            let c = &mut *(std::ptr::addr_of_mut!((*p).c) as *mut MaybeUninit<Closest>);
            Closest::start(c, bvh, ray, t_max);
            std::ptr::addr_of_mut!((*p).k).write(k);
            std::ptr::addr_of_mut!((*p).s).write(s);
        }
    }

    /// This slot made a copy of `from` (the stack's live items only).
    #[inline(always)]
    fn take(&mut self, from: &Slot<S>) {
        let (c, f) = (&mut self.c, &from.c);
        c.r = f.r;
        c.cur = f.cur;
        c.t_max = f.t_max;
        c.found = f.found;
        c.stack.len = f.stack.len;
        c.stack.items[..f.stack.len].copy_from_slice(&f.stack.items[..f.stack.len]);
        self.k = from.k;
        self.s = from.s;
    }
}

impl WideBvh {
    /// The closest hits of `rays` up to `t_max`, `K` rays in flight (see the module's
    /// documentation): for ray `k`, `hit(k, &mut state, prim, t_max)` tests primitive
    /// `prim` as [`WideBvh::intersect`]'s `hit` does, with `state` the ray's own (`init` at
    /// its start), and when its traversal ends `done(k, found, &state)` gets whether it hit
    /// anything (in the order the traversals end). `leaf(first, count)` prefetches the
    /// primitives of a leaf (whose memory is the caller's).
    #[inline(always)]
    pub fn intersect_stream<const K: usize, S: Copy>(
        &self,
        rays: &[Ray],
        t_max: f32,
        init: S,
        mut hit: impl FnMut(usize, &mut S, usize, f32) -> Option<f32>,
        leaf: impl Fn(usize, usize),
        mut done: impl FnMut(usize, bool, &S),
    ) {
        if self.root == EMPTY {
            for k in 0..rays.len() {
                done(k, false, &init);
            }
            return;
        }
        // The rays in flight: `slots[..live]`, each taking a step in turn.
        let mut slots: [MaybeUninit<Slot<S>>; K] = [const { MaybeUninit::uninit() }; K];
        let mut live = 0;
        while live < K && live < rays.len() {
            Slot::start(&mut slots[live], self, &rays[live], t_max, live, init);
            live += 1;
        }
        let mut next = live;
        let mut i = 0;
        while live > 0 {
            // SAFETY: the slots below `live` are started (above, or below when a ray ends).
            let slot = unsafe { slots[i].assume_init_mut() };
            let (k, s) = (slot.k, &mut slot.s);
            if slot.c.step(self, &mut |p, t| hit(k, s, p, t)) {
                self.prefetch_step(slot.c.cur, &leaf);
                i += 1;
            } else {
                done(k, slot.c.found, &slot.s);
                if next < rays.len() {
                    Slot::start(&mut slots[i], self, &rays[next], t_max, next, init);
                    next += 1;
                    i += 1;
                } else {
                    // The last ray in flight takes this slot (and the next turn).
                    live -= 1;
                    if i < live {
                        let (head, tail) = slots.split_at_mut(live);
                        // SAFETY: both were started (below the old `live`).
                        unsafe { head[i].assume_init_mut().take(tail[0].assume_init_ref()) };
                    }
                }
            }
            if i >= live {
                i = 0;
            }
        }
    }

    /// Prefetches what a step at `c` reads: a node's bounds and children (112 bytes on 16,
    /// so two or three cache lines), or by `leaf` a leaf's primitives.
    #[inline(always)]
    fn prefetch_step(&self, c: ChildRef, leaf: &impl Fn(usize, usize)) {
        if c & LEAF != 0 {
            leaf(((c & !LEAF) >> 4) as usize, (c & 15) as usize);
        } else {
            let p = self.node(c) as *const Node4 as *const u8;
            const LAST: usize = std::mem::size_of::<Node4>() - 1;
            for off in [0, 64, LAST] {
                // SAFETY: each offset lies inside the node.
                prefetch(unsafe { &*p.add(off) });
            }
        }
    }
}
