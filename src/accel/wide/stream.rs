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
//! of a ray's state (and [`WideBvh::occluded_stream`]'s those of [`WideBvh::occluded`],
//! `any_step!`); the interleaving changes only when its steps run, never what they
//! compute.

use super::{
    child_key, child_of_key, lowest, sort_keys, ChildRef, Node, RayBoxes, Stack, WideBvh, EMPTY,
    LEAF, WIDEN, WIDTH,
};
use crate::accel::prefetch;
use crate::geometry::Ray;
use std::mem::MaybeUninit;

/// One ray's traversal between steps: its prepared ray, the postponed children (`E`: a
/// child reference, with its entry distance for the closest hit), the node or leaf its next
/// step visits, its `t_max` (the distance of the nearest hit so far, for the closest hit),
/// and whether it hit anything.
pub(crate) struct Trav<E: Copy> {
    r: RayBoxes,
    stack: Stack<E>,
    cur: ChildRef,
    t_max: f32,
    found: bool,
}

/// A closest-hit traversal.
pub(crate) type Closest = Trav<(u32, f32)>;
/// An occlusion (any-hit) traversal.
pub(crate) type Any = Trav<u32>;

impl<E: Copy> Trav<E> {
    /// Starts the traversal of `ray` up to `t_max` in `slot` (left uninitialised until now:
    /// only the stack's length is written, not its items) at the root of `bvh`, which must
    /// not be `EMPTY`.
    #[inline(always)]
    fn start(slot: &mut MaybeUninit<Trav<E>>, bvh: &WideBvh, ray: &Ray, t_max: f32) {
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
        }
    }

    /// This traversal made a copy of `f` (the stack's live items only).
    #[inline(always)]
    fn take(&mut self, f: &Trav<E>) {
        self.r = f.r;
        self.cur = f.cur;
        self.t_max = f.t_max;
        self.found = f.found;
        self.stack.len = f.stack.len;
        self.stack.items[..f.stack.len].copy_from_slice(&f.stack.items[..f.stack.len]);
    }
}

/// One step of a traversal of ray `k` with the caller's state `s` for it, with `hit(k, s,
/// prim, t_max)` the caller's primitive test. (`k` and `s` are passed rather than captured
/// by a closure around `hit`: such a closure was built in memory at every step, leaf or
/// not, and kept the triangle test out of line; see docs/performance.md.)
pub(crate) trait Step {
    /// What the primitive test answers.
    type Hit;
    /// One step; false when the traversal is over.
    fn step<S, F: FnMut(usize, &mut S, usize, f32) -> Self::Hit>(
        &mut self,
        bvh: &WideBvh,
        k: usize,
        s: &mut S,
        hit: &mut F,
    ) -> bool;
}

impl Step for Closest {
    type Hit = Option<f32>;
    /// One step of [`WideBvh::intersect`]'s traversal (`closest_step!`).
    #[inline(always)]
    fn step<S, F: FnMut(usize, &mut S, usize, f32) -> Option<f32>>(
        &mut self,
        bvh: &WideBvh,
        k: usize,
        s: &mut S,
        hit: &mut F,
    ) -> bool {
        closest_step!(
            bvh,
            self.r,
            self.stack,
            self.cur,
            self.t_max,
            self.found,
            |p, t| hit(k, s, p, t),
            true,
            { return true },
            { return false }
        )
    }
}

impl Step for Any {
    type Hit = bool;
    /// One step of [`WideBvh::occluded`]'s traversal (`any_step!`); a hit ends it.
    // (The macro places `$next` and `$done` in tail position as well as in a loop's body.)
    #[allow(clippy::needless_return)]
    #[inline(always)]
    fn step<S, F: FnMut(usize, &mut S, usize, f32) -> bool>(
        &mut self,
        bvh: &WideBvh,
        k: usize,
        s: &mut S,
        hit: &mut F,
    ) -> bool {
        any_step!(
            bvh,
            self.r,
            self.stack,
            self.cur,
            self.t_max,
            |p, t| hit(k, s, p, t),
            true,
            { return true },
            {
                self.found = true;
                return false;
            },
            { return false }
        )
    }
}

/// A ray in flight in [`WideBvh::stream`]: its traversal, its index in the batch, and the
/// caller's state for it.
struct Slot<E: Copy, S> {
    c: Trav<E>,
    k: usize,
    s: S,
}

impl<E: Copy, S: Copy> Slot<E, S> {
    /// Starts ray `k` in `slot` (see [`Trav::start`]).
    #[inline(always)]
    fn start(
        slot: &mut MaybeUninit<Slot<E, S>>,
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
            let c = &mut *(std::ptr::addr_of_mut!((*p).c) as *mut MaybeUninit<Trav<E>>);
            Trav::start(c, bvh, ray, t_max);
            std::ptr::addr_of_mut!((*p).k).write(k);
            std::ptr::addr_of_mut!((*p).s).write(s);
        }
    }

    /// This slot made a copy of `from`.
    #[inline(always)]
    fn take(&mut self, from: &Slot<E, S>) {
        self.c.take(&from.c);
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
        hit: impl FnMut(usize, &mut S, usize, f32) -> Option<f32>,
        leaf: impl Fn(usize, usize),
        done: impl FnMut(usize, bool, &S),
    ) {
        self.stream::<(u32, f32), K, S>(rays, |_| t_max, init, hit, leaf, done);
    }

    /// Whether each of `rays` hits anything before its `t_max[k]`, `K` rays in flight:
    /// `hit(k, prim, t_max)` tests primitive `prim` as [`WideBvh::occluded`]'s `hit` does,
    /// and `done(k, blocked)` gets each ray's answer as its traversal ends; `leaf` as for
    /// [`WideBvh::intersect_stream`].
    #[inline(always)]
    pub fn occluded_stream<const K: usize>(
        &self,
        rays: &[Ray],
        t_max: &[f32],
        mut hit: impl FnMut(usize, usize, f32) -> bool,
        leaf: impl Fn(usize, usize),
        mut done: impl FnMut(usize, bool),
    ) {
        self.stream::<u32, K, ()>(
            rays,
            |k| t_max[k],
            (),
            |k, _, p, t| hit(k, p, t),
            leaf,
            |k, blocked, _| done(k, blocked),
        );
    }

    /// The traversals of `rays`, `K` in flight, each a step in turn (see
    /// [`WideBvh::intersect_stream`]).
    #[inline(always)]
    fn stream<E: Copy, const K: usize, S: Copy>(
        &self,
        rays: &[Ray],
        t_max: impl Fn(usize) -> f32,
        init: S,
        mut hit: impl FnMut(usize, &mut S, usize, f32) -> <Trav<E> as Step>::Hit,
        leaf: impl Fn(usize, usize),
        mut done: impl FnMut(usize, bool, &S),
    ) where
        Trav<E>: Step,
    {
        if self.root == EMPTY {
            for k in 0..rays.len() {
                done(k, false, &init);
            }
            return;
        }
        // The rays in flight: `slots[..live]`, each taking a step in turn.
        let mut slots: [MaybeUninit<Slot<E, S>>; K] = [const { MaybeUninit::uninit() }; K];
        let mut live = 0;
        while live < K && live < rays.len() {
            let t = t_max(live);
            Slot::start(&mut slots[live], self, &rays[live], t, live, init);
            live += 1;
        }
        let mut next = live;
        let mut i = 0;
        while live > 0 {
            debug_assert!(i < live && live <= K);
            // SAFETY: `i` < `live` ≤ K, and the slots below `live` are started (above, or
            // below when a ray ends).
            let slot = unsafe { slots.get_unchecked_mut(i).assume_init_mut() };
            if slot.c.step(self, slot.k, &mut slot.s, &mut hit) {
                self.prefetch_step(slot.c.cur, &leaf);
                i += 1;
            } else {
                done(slot.k, slot.c.found, &slot.s);
                if next < rays.len() {
                    let t = t_max(next);
                    Slot::start(&mut slots[i], self, &rays[next], t, next, init);
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

    /// Prefetches what a step at `c` reads: a node's bounds and children (224 bytes on 32,
    /// so four cache lines), or by `leaf` a leaf's primitives.
    #[inline(always)]
    fn prefetch_step(&self, c: ChildRef, leaf: &impl Fn(usize, usize)) {
        if c & LEAF != 0 {
            leaf(((c & !LEAF) >> 4) as usize, (c & 15) as usize);
        } else {
            let p = self.node(c) as *const Node as *const u8;
            const LAST: usize = std::mem::size_of::<Node>() - 1;
            for off in [0, 64, 128, LAST] {
                // SAFETY: each offset lies inside the node.
                prefetch(unsafe { &*p.add(off) });
            }
        }
    }
}
