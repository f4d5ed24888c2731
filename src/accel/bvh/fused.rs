//! The build over clusters in two stages, so that the binary tree never exists whole:
//! 1. the top of the binary tree, down to subtrees over at most [`FUSE_MAX`] primitives,
//!    each left as a stub (its bounds and primitives, see [`BvhNode::is_stub`]); the top is
//!    collapsed into the top of the wide tree at once, the stubs' slots left open;
//! 2. each subtree built into a small buffer of the thread that takes it and collapsed while
//!    its nodes are still in the cache, its wide nodes placed in the tree's array after those
//!    of the subtrees before it.
//!
//! Why: building the whole binary tree and then collapsing it wrote 338 MB of binary nodes
//! at 10 M triangles (32 bytes a node, about 1.07 nodes a primitive over clusters), all of
//! it memory the process touched first, and read it twice from memory (to count each
//! parallel part's wide nodes, then to write them), and on hosts that charge dearly for
//! fresh memory that was a large share of the build (docs/performance.md, "Fresh memory on
//! this VM"). Now the binary nodes of a subtree live in about half a megabyte that each
//! thread reuses, and only the top's few thousand nodes are written to a large array (at
//! scattered places of an allocation that is never touched elsewhere).
//!
//! The wide tree is the collapse of the same binary tree, except that a wide node of the top
//! never adopts a stub's children (a stub is a wide node of its own, or a leaf): at 10 M
//! triangles about a thousand of the 1.9 M wide nodes.
//!
//! Determinism: the subtrees are numbered depth first, taken by the threads in that order,
//! and each is placed as soon as all those before it are, so the array depends on the input
//! alone, never on the threads.

use super::{
    bounds_weight_of, build_node, finish, inner, prims_of, slots_of, step, stub, BvhNode, Kind,
    Nodes, PrimRef, Split, Step, Sub, PARALLEL_MIN,
};
use crate::accel::wide::{rebased, ChildRef, Collapse, Node, WideBvh, MERGE_MAX};
use crate::accel::{huge_pages, BuildTimes};
use crate::geometry::Aabb;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::mem::MaybeUninit;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// Subtrees over at most this many primitives are built and collapsed whole by one thread:
/// their binary nodes take at most about 600 kB (a primitive's cluster share of a node, and
/// its leaf), which stays in a core's L2 cache.
pub(super) const FUSE_MAX: usize = 1 << 14;

/// What the top's parent records of a stub. (Its leaves are not known until its subtree is
/// built; the nodes of the top hold more than `FUSE_MAX` primitives, so the collapse, which
/// reads the leaves and costly flag only of nodes over at most `MERGE_MAX`, never reads
/// theirs.)
const STUB_SUB: Sub = Sub {
    leaves: 15,
    costly: false,
};

/// A stub's subtree, left to the second stage: what `build_node` needs to build it, and the
/// node slots it takes.
struct Task<'a> {
    refs: &'a mut [PrimRef],
    order: &'a mut [u32],
    root: Root,
    slots: usize,
}

/// The wide tree over the references `refs` (standing for the primitives `0..n`; their
/// trees below them, as `kind` builds them), fringe subtrees merged by `merge_weight`, and
/// the primitives' order. Marks its two stages in `times`.
pub(super) fn build<K: Kind>(
    kind: &K,
    refs: &mut [PrimRef],
    n: usize,
    merge_weight: f32,
    times: &mut BuildTimes,
) -> (WideBvh, Vec<u32>) {
    let (bounds, cbounds, total) = bounds_weight_of(refs, K::weight);
    debug_assert_eq!(prims_of(total), n);
    let mut order = huge_pages::zeroed(n);
    // The binary tree's slots, of which the top writes a few thousand and nothing else any.
    let slots = slots_of(total);
    let mut top_nodes: Vec<MaybeUninit<BvhNode>> = huge_pages::sparse(slots);
    // SAFETY: MaybeUninit needs no initialisation.
    unsafe { top_nodes.set_len(slots) };
    let mut found = Vec::new();
    let root = Root {
        first: 0,
        depth: 0,
        bounds,
        cbounds,
    };
    let _ = top(kind, &mut top_nodes, 0, &mut order, refs, root, &mut found);
    // The stubs by their slots (depth first, as their subtrees' primitives lie in the order).
    let mut tasks: BTreeMap<usize, Task> = found.into_iter().collect();
    // Collapse the top; where it would open a stub, build the stub's node and collapse again.
    let (wide_top, open, root_is_stub) = loop {
        // SAFETY: `top` and `expand` wrote the root, and both children of every inner node
        // they wrote that is not a stub.
        let view = unsafe { Nodes::new(&top_nodes) };
        if view.node(0).is_stub() {
            break (Vec::new(), Vec::new(), true);
        }
        let (mut wide_top, mut open) = (Vec::new(), Vec::new());
        let collapse = Collapse::new(view, merge_weight);
        let root = collapse.subtree(0, &mut wide_top, &mut open);
        debug_assert_eq!(root, 0, "the top's root is an inner node");
        let wanted = collapse.wanted();
        if wanted.is_empty() {
            break (wide_top, open, false);
        }
        for k in wanted {
            // (A stub two wide nodes would open is expanded once.)
            if let Some(t) = tasks.remove(&k) {
                expand(kind, &mut top_nodes, k, t, &mut tasks);
            }
        }
    };
    times.mark("top of the tree");
    let stubs: Vec<usize> = tasks.keys().copied().collect();
    // A subtree's wide nodes are at most its binary inner nodes, half its slots.
    let most = wide_top.len() + tasks.values().map(|t| t.slots / 2).sum::<usize>();
    let mut nodes: Vec<Node> = huge_pages::with_capacity(most);
    let (roots, len) = subtrees(
        kind,
        tasks.into_values().collect(),
        merge_weight,
        &mut nodes.spare_capacity_mut()[..most],
        wide_top.len(),
    );
    let mut wide_top = wide_top;
    for (w, slot, k) in open {
        let j = stubs
            .binary_search(&k)
            .expect("every stub is a subtree of the second stage");
        wide_top[w].set_child(slot, roots[j]);
    }
    drop(top_nodes);
    // SAFETY: `subtrees` wrote the slots from `wide_top.len()` to `len`, and the top fills
    // those before.
    unsafe {
        std::ptr::copy_nonoverlapping(wide_top.as_ptr(), nodes.as_mut_ptr(), wide_top.len());
        nodes.set_len(len);
    }
    // (No `shrink_to_fit`: the spare capacity was never written, so it holds no memory,
    // while glibc may move a shrunk array into memory never advised as huge pages, where
    // the traversal's node loads miss the TLB.)
    times.mark("subtrees");
    let root = if root_is_stub { roots[0] } else { 0 };
    (WideBvh::from_parts(nodes, root, bounds), order)
}

/// Where a subtree lies and what its root holds: its first primitive's position in the
/// order, its depth, and the bounds of its references and of their doubled centroids.
#[derive(Clone, Copy)]
pub(super) struct Root {
    pub(super) first: usize,
    pub(super) depth: usize,
    pub(super) bounds: Aabb,
    pub(super) cbounds: Aabb,
}

/// The first stage: writes the top of the binary tree over `refs` into `nodes` (slots from
/// `at` on) as `build_node` would, down to nodes over at most `FUSE_MAX` primitives, which
/// [`place`] makes stubs (appended to `tasks` with their slots, depth first) or builds.
fn top<'a, K: Kind>(
    kind: &K,
    nodes: &mut [MaybeUninit<BvhNode>],
    at: usize,
    order: &'a mut [u32],
    refs: &'a mut [PrimRef],
    root: Root,
    tasks: &mut Vec<(usize, Task<'a>)>,
) -> Sub {
    let w = order.len();
    if w <= FUSE_MAX {
        return place(kind, nodes, at, order, refs, root, tasks);
    }
    let Root {
        first,
        depth,
        bounds,
        cbounds,
    } = root;
    let Step::Split(split) = step::<K>(refs, w, depth, &bounds, &cbounds) else {
        // (A node over more than `FUSE_MAX` primitives is always split: clusters hold at
        // most eight, so it has more references than a leaf or a sweep takes.)
        return place(kind, nodes, at, order, refs, root, tasks);
    };
    let (head, [left, right]) = children(nodes, order, refs, first, depth, &bounds, split);
    let (a, b) = if left.3.len().min(right.3.len()) >= PARALLEL_MIN {
        let mut right_tasks = Vec::new();
        let (a, b) = rayon::join(
            || top(kind, left.0, at + 1, left.3, left.2, left.1, tasks),
            || {
                let r = right;
                top(kind, r.0, at + 1 + r.4, r.3, r.2, r.1, &mut right_tasks)
            },
        );
        tasks.append(&mut right_tasks);
        (a, b)
    } else {
        (
            top(kind, left.0, at + 1, left.3, left.2, left.1, tasks),
            top(
                kind,
                right.0,
                at + 1 + right.4,
                right.3,
                right.2,
                right.1,
                tasks,
            ),
        )
    };
    finish(head, a.join(b))
}

/// One child of a split node: its slots, where it lies and its bounds, its references and
/// its part of the order, and its slots' offset from the left child's first.
pub(super) type Child<'n, 'a> = (
    &'n mut [MaybeUninit<BvhNode>],
    Root,
    &'a mut [PrimRef],
    &'a mut [u32],
    usize,
);

/// Writes the inner node that `split` makes of `nodes[0]` (over `refs` and `order`), and
/// returns it with its children's parts.
#[allow(clippy::too_many_arguments)]
pub(super) fn children<'n, 'a>(
    nodes: &'n mut [MaybeUninit<BvhNode>],
    order: &'a mut [u32],
    refs: &'a mut [PrimRef],
    first: usize,
    depth: usize,
    bounds: &Aabb,
    split: Split,
) -> (&'n mut MaybeUninit<BvhNode>, [Child<'n, 'a>; 2]) {
    let Split {
        mid,
        wl,
        l: (lb, lc),
        r: (rb, rc),
    } = split;
    let w = order.len();
    // (The weight on the left, not the references, lays out the nodes and the order.)
    let (sl, wl) = (slots_of(wl), prims_of(wl));
    let (head, rest) = nodes.split_first_mut().unwrap();
    head.write(inner(bounds, 1 + sl, w));
    let (lr, rr) = refs.split_at_mut(mid);
    let (ln, rn) = rest.split_at_mut(sl);
    let (lo, ro) = order.split_at_mut(wl);
    let d = depth + 1;
    let at = |first, bounds, cbounds| Root {
        first,
        depth: d,
        bounds,
        cbounds,
    };
    (
        head,
        [
            (ln, at(first, lb, lc), lr, lo, 0),
            (rn, at(first + wl, rb, rc), rr, ro, sl),
        ],
    )
}

/// A node below the top: a stub, its subtree left to the second stage (appended to `tasks`
/// with its slot `at`), where it is surely an inner node and no fringe one (more
/// references than a leaf takes, more primitives than the collapse merges into one leaf),
/// so that the collapse can judge it without its children; else (a leaf or a few
/// primitives) built here whole.
fn place<'a, K: Kind>(
    kind: &K,
    nodes: &mut [MaybeUninit<BvhNode>],
    at: usize,
    order: &'a mut [u32],
    refs: &'a mut [PrimRef],
    root: Root,
    tasks: &mut Vec<(usize, Task<'a>)>,
) -> Sub {
    let w = order.len();
    if refs.len() <= K::MAX_LEAF || w <= MERGE_MAX as usize {
        let Root {
            first,
            depth,
            bounds,
            cbounds,
        } = root;
        return build_node(kind, nodes, order, refs, first, depth, bounds, cbounds);
    }
    nodes[0].write(stub(&root.bounds, root.first, w));
    let slots = nodes.len();
    tasks.push((
        at,
        Task {
            refs,
            order,
            root,
            slots,
        },
    ));
    STUB_SUB
}

/// Builds stub `k` (of `nodes`, the whole top) one level further, as `build_node` would: its
/// children become stubs themselves or are built whole (see [`place`]).
fn expand<'a, K: Kind>(
    kind: &K,
    nodes: &mut [MaybeUninit<BvhNode>],
    k: usize,
    t: Task<'a>,
    tasks: &mut BTreeMap<usize, Task<'a>>,
) {
    let Task {
        refs,
        order,
        root,
        slots,
    } = t;
    let here = &mut nodes[k..k + slots];
    let w = order.len();
    let Root {
        first,
        depth,
        bounds,
        cbounds,
    } = root;
    let Step::Split(split) = step::<K>(refs, w, depth, &bounds, &cbounds) else {
        // (A leaf or a small node: built whole, where `build_node` decides it again just so,
        // as the step changed nothing.)
        let _ = build_node(kind, here, order, refs, first, depth, bounds, cbounds);
        return;
    };
    let (head, [left, right]) = children(here, order, refs, first, depth, &bounds, split);
    let mut found = Vec::new();
    let a = place(kind, left.0, k + 1, left.3, left.2, left.1, &mut found);
    let b = place(
        kind,
        right.0,
        k + 1 + right.4,
        right.3,
        right.2,
        right.1,
        &mut found,
    );
    let _ = finish(head, a.join(b));
    tasks.extend(found);
}

/// The second stage's bookkeeping: subtrees are placed in the order of their numbers, each
/// after those before it.
struct Placing {
    /// Where each subtree's references end in memory (they lie in its order), and the end
    /// of those given back to the system (see `subtrees`).
    ends: Vec<usize>,
    released: usize,
    /// The next subtree to place, and where its nodes go.
    next: usize,
    cursor: usize,
    /// Subtrees built and collapsed but not placed (one before them is not done): their
    /// number, wide nodes, numbered from 0, and root reference.
    done: Vec<(usize, Vec<Node>, ChildRef)>,
    /// Each subtree's root reference, once placed.
    roots: Vec<ChildRef>,
    /// Emptied node vectors, for reuse.
    spare: Vec<Vec<Node>>,
}

impl Placing {
    /// Places every done subtree that can be: returns where each goes, with its nodes, and
    /// the memory of the references that all placed subtrees are done with, in whole huge
    /// pages not returned before.
    fn ready(&mut self, end: usize) -> (Vec<Placed>, Option<(usize, usize)>) {
        let mut ready = Vec::new();
        while let Some(i) = self.done.iter().position(|d| d.0 == self.next) {
            let (j, nodes, root) = self.done.swap_remove(i);
            let base = self.cursor;
            self.roots[j] = rebased(root, base as u32);
            self.cursor += nodes.len();
            assert!(
                self.cursor <= end,
                "more wide nodes than binary inner nodes"
            );
            self.next += 1;
            ready.push((base, nodes));
        }
        let done =
            self.next.checked_sub(1).map_or(0, |j| self.ends[j]) & !(huge_pages::HUGE_PAGE - 1);
        let release = (done > self.released).then(|| (self.released, done - self.released));
        self.released = self.released.max(done);
        (ready, release)
    }
}

/// A subtree's place in the output array, and its wide nodes to copy there.
type Placed = (usize, Vec<Node>);

/// The output array of the second stage, written at disjoint places from several threads.
struct Out(*mut MaybeUninit<Node>);
// SAFETY: each place is written once, by the thread that placed the subtree it belongs to
// (see `Placing::ready`, which hands out each stretch once).
unsafe impl Sync for Out {}

/// The second stage: builds and collapses each task's subtree, and writes its wide nodes
/// into `out` from `start` on, in the tasks' order. Returns each subtree's root reference
/// and the end of the written part of `out`.
fn subtrees<K: Kind>(
    kind: &K,
    tasks: Vec<Task<'_>>,
    merge_weight: f32,
    out: &mut [MaybeUninit<Node>],
    start: usize,
) -> (Vec<ChildRef>, usize) {
    let count = tasks.len();
    let ends = tasks
        .iter()
        .map(|t| t.refs.as_ptr_range().end as usize)
        .collect();
    let released = tasks.first().map_or(0, |t| t.refs.as_ptr() as usize);
    // The release of placed subtrees' references relies on their lying in the tasks' order.
    debug_assert!(
        tasks
            .windows(2)
            .all(|w| w[0].refs.as_ptr_range().end <= w[1].refs.as_ptr()),
        "the subtrees' references lie in their order"
    );
    let tasks: Vec<Mutex<Option<Task>>> = tasks.into_iter().map(|t| Mutex::new(Some(t))).collect();
    let next = AtomicUsize::new(0);
    let placing = Mutex::new(Placing {
        ends,
        released,
        next: 0,
        cursor: start,
        done: Vec::new(),
        roots: vec![0; count],
        spare: Vec::new(),
    });
    let end = out.len();
    let out = Out(out.as_mut_ptr());
    let threads = rayon::current_num_threads();
    (0..threads).into_par_iter().with_max_len(1).for_each(|_| {
        let out = &out;
        let mut scratch: Vec<MaybeUninit<BvhNode>> = Vec::new();
        loop {
            let j = next.fetch_add(1, Ordering::Relaxed);
            if j >= count {
                break;
            }
            let t = tasks[j].lock().unwrap().take().unwrap();
            scratch.clear();
            scratch.reserve(t.slots);
            // SAFETY: MaybeUninit needs no initialisation.
            unsafe { scratch.set_len(t.slots) };
            let Root {
                first,
                depth,
                bounds,
                cbounds,
            } = t.root;
            let _ = build_node(
                kind,
                &mut scratch,
                t.order,
                t.refs,
                first,
                depth,
                bounds,
                cbounds,
            );
            let mut wide = placing.lock().unwrap().spare.pop().unwrap_or_default();
            wide.clear();
            // SAFETY: `build_node` wrote the root and both children of every inner node.
            let nodes = unsafe { Nodes::new(&scratch) };
            let mut open = Vec::new();
            let root = Collapse::new(nodes, merge_weight).subtree(0, &mut wide, &mut open);
            debug_assert!(open.is_empty(), "no stubs below the top");
            let (ready, release) = {
                let mut p = placing.lock().unwrap();
                p.done.push((j, wide, root));
                p.ready(end)
            };
            if let Some((start, len)) = release {
                // SAFETY: these references belong to subtrees that are built (their tasks,
                // which held them, dropped), and nobody reads them again.
                unsafe { huge_pages::release(start, len) };
            }
            for (base, wide) in ready {
                for (k, node) in wide.iter().enumerate() {
                    // SAFETY: `ready` gave this subtree the places base..base + len,
                    // below `end`, and no other.
                    unsafe { (*out.0.add(base + k)).write(node.rebased(base as u32)) };
                }
                placing.lock().unwrap().spare.push(wide);
            }
        }
    });
    let p = placing.into_inner().unwrap();
    assert_eq!(p.next, count, "every subtree placed");
    (p.roots, p.cursor)
}
