//! An obvhs [`Bvh2`] re-laid for traversal: sibling nodes stored together, both boxes tested
//! in one pass of 4-wide arithmetic, and a small stack that is not zeroed per query.
//!
//! obvhs's own traversal (`Bvh2::ray_traverse`) reads two 48-byte nodes per step, tests their
//! boxes one after the other, and zeroes a 96-entry stack on every query (a `memset` that
//! shows in CUP's and SORT's profiles). Here a step reads one 64-byte [`Pair`]: per axis the
//! lanes hold (left min, right min, left max, right max), so one subtraction and one
//! multiplication give both children's slab distances.
//!
//! The answers must stay obvhs's bit for bit (the committed images depend on them), and a
//! closest hit depends on the order in which leaves are visited (two triangles at the same
//! distance: the first found wins). So the traversal is obvhs's step for step: test both
//! children, the nearer first (the left on a tie), intersect a hit leaf at once, descend into
//! the nearer inner child and push the farther. Each lane computes obvhs's `Aabb::intersect_ray`
//! operations on the same values; the min/max over the axes are taken in another order, which
//! is exact since no value is NaN (the inverse direction is finite, obvhs's `safe_inverse`).

use glam::{Vec3A, Vec4, Vec4Swizzles};
use obvhs::{bvh2::Bvh2, ray::Ray};

/// Deepest stack a traversal needs; a tree needing more is not converted (the caller keeps
/// obvhs's traversal). The CUP mug needs about 20, SORT's boxes about 10.
pub(super) const STACK: usize = 64;

/// One child of a pair: a leaf (`count` primitives from `first`) or an inner node whose
/// children are the pair `first` (`count` = 0).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Child {
    pub(super) first: u32,
    pub(super) count: u32,
}

/// Two sibling nodes: their boxes per axis as (left min, right min, left max, right max).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Pair {
    slabs: [Vec4; 3],
    children: [Child; 2],
}

/// The ray as the pair test needs it: origin and inverse direction splat per axis.
pub(super) struct Splat {
    pub(super) o: [Vec4; 3],
    pub(super) inv: [Vec4; 3],
}

impl Splat {
    #[inline(always)]
    pub(super) fn new(ray: &Ray) -> Self {
        let (o, i) = (ray.origin, ray.inv_direction);
        Self {
            o: [Vec4::splat(o.x), Vec4::splat(o.y), Vec4::splat(o.z)],
            inv: [Vec4::splat(i.x), Vec4::splat(i.y), Vec4::splat(i.z)],
        }
    }
}

impl Pair {
    /// Both children's `Aabb::intersect_ray`: entry distance, or infinity for a miss.
    #[inline(always)]
    fn entries(&self, r: &Splat) -> (f32, f32) {
        let axis = |a: usize| {
            // Lanes (t1 left, t1 right, t2 left, t2 right); the swap pairs each t1 with its t2.
            let t = (self.slabs[a] - r.o[a]) * r.inv[a];
            let s = t.zwxy();
            (t.min(s), t.max(s))
        };
        let (nx, fx) = axis(0);
        let (ny, fy) = axis(1);
        let (nz, fz) = axis(2);
        let near = nx.max(ny).max(nz);
        let far = fx.min(fy).min(fz);
        let hit = far.cmpge(near) & far.cmpge(Vec4::ZERO);
        let t = Vec4::select(hit, near, Vec4::INFINITY);
        (t.x, t.y)
    }
}

/// A [`Bvh2`]'s tree as [`Pair`]s, traversed in obvhs's order (see the module's doc).
#[derive(Clone, Debug)]
pub struct PairBvh {
    root_min: Vec3A,
    root_max: Vec3A,
    /// The root itself when it is a leaf (`count` > 0), else the root's pair (`first` = 0).
    root: Child,
    pairs: Vec<Pair>,
}

impl PairBvh {
    /// The pair layout of `bvh`, or None when its traversal could need more than [`STACK`]
    /// entries (or it is empty). A leaf keeps its primitives' range (first, count).
    pub fn new(bvh: &Bvh2) -> Option<Self> {
        Self::with_leaves(bvh, |first, _| first)
    }

    /// [`PairBvh::new`], with each leaf's `first` replaced by `leaf(first, count)` (called
    /// once per leaf, depth first: e.g. where the caller stored that leaf's primitives).
    pub fn with_leaves(bvh: &Bvh2, mut leaf: impl FnMut(u32, u32) -> u32) -> Option<Self> {
        let root = bvh.nodes.first()?;
        let mut out = Self {
            root_min: root.aabb().min,
            root_max: root.aabb().max,
            root: Child::default(),
            pairs: Vec::new(),
        };
        if root.is_leaf() {
            out.root = Child {
                first: leaf(root.first_index, root.prim_count),
                count: root.prim_count,
            };
            return Some(out);
        }
        let depth = out.add_pair(bvh, root.first_index as usize, &mut leaf);
        out.root.first = 0;
        (depth <= STACK).then_some(out)
    }

    /// Appends the pair of nodes `first`, `first + 1` and, depth first, the pairs below them;
    /// returns the depth of the subtree in pairs (a bound on the stack it needs).
    fn add_pair(
        &mut self,
        bvh: &Bvh2,
        first: usize,
        leaf: &mut impl FnMut(u32, u32) -> u32,
    ) -> usize {
        let (l, r) = (&bvh.nodes[first], &bvh.nodes[first + 1]);
        let (a, b) = (l.aabb(), r.aabb());
        let lanes = |k: usize| Vec4::new(a.min[k], b.min[k], a.max[k], b.max[k]);
        let index = self.pairs.len();
        self.pairs.push(Pair {
            slabs: [lanes(0), lanes(1), lanes(2)],
            children: [Child::default(); 2],
        });
        let mut depth = 0;
        for (side, node) in [l, r].into_iter().enumerate() {
            let child = if node.is_leaf() {
                Child {
                    first: leaf(node.first_index, node.prim_count),
                    count: node.prim_count,
                }
            } else {
                let below = self.pairs.len() as u32;
                depth = depth.max(self.add_pair(bvh, node.first_index as usize, leaf));
                Child {
                    first: below,
                    count: 0,
                }
            };
            self.pairs[index].children[side] = child;
        }
        depth + 1
    }

    /// Closest hit, as obvhs's `Bvh2::ray_traverse`: `test(ray, primitive)` gives a distance
    /// (infinity for a miss; `ray.tmax` is the closest so far); returns (distance, primitive).
    #[inline(always)]
    pub fn closest(
        &self,
        mut ray: Ray,
        mut test: impl FnMut(&Ray, usize) -> f32,
    ) -> Option<(f32, u32)> {
        let mut found = None;
        self.traverse(&mut ray, |ray, first, count| {
            for id in first..first + count {
                let t = test(ray, id as usize);
                if t < ray.tmax {
                    found = Some(id);
                    ray.tmax = t;
                }
            }
            true
        });
        found.map(|id| (ray.tmax, id))
    }

    /// Whether some primitive lies on the ray before `ray.tmax`, as obvhs's
    /// `Bvh2::ray_traverse_miss` (negated): `test` as for [`PairBvh::closest`].
    #[inline(always)]
    pub fn any(&self, mut ray: Ray, mut test: impl FnMut(&Ray, usize) -> f32) -> bool {
        let mut hit = false;
        self.traverse(&mut ray, |ray, first, count| {
            hit = (first..first + count).any(|id| test(ray, id as usize) < ray.tmax);
            !hit
        });
        hit
    }

    /// obvhs's `Bvh2::ray_traverse_dynamic`: `leaf(ray, first, count)` tests a hit leaf's
    /// primitives (it may shorten `ray.tmax`) and returns false to stop; `first` is what
    /// [`PairBvh::with_leaves`] stored.
    #[inline(always)]
    pub fn traverse(&self, ray: &mut Ray, mut leaf: impl FnMut(&mut Ray, u32, u32) -> bool) {
        let root = obvhs::aabb::Aabb::new(self.root_min, self.root_max);
        if root.intersect_ray(ray) >= ray.tmax {
            return;
        }
        if self.root.count > 0 {
            leaf(ray, self.root.first, self.root.count);
            return;
        }
        let splat = Splat::new(ray);
        let mut stack = [0u32; STACK];
        let mut top = 0;
        let mut current = 0u32;
        loop {
            let pair = &self.pairs[current as usize];
            let (t0, t1) = pair.entries(&splat);
            let (near, far, t_near, t_far) = if t0 > t1 {
                (pair.children[1], pair.children[0], t1, t0)
            } else {
                (pair.children[0], pair.children[1], t0, t1)
            };
            // As obvhs: the farther child is tested against tmax after the nearer leaf's hits.
            let mut go = [false; 2];
            for (k, (child, t)) in [(near, t_near), (far, t_far)].into_iter().enumerate() {
                if t < ray.tmax {
                    if child.count == 0 {
                        go[k] = true;
                    } else if !leaf(ray, child.first, child.count) {
                        return;
                    }
                }
            }
            current = match go {
                [true, true] => {
                    stack[top] = far.first;
                    top += 1;
                    near.first
                }
                [true, false] => near.first,
                [false, true] => far.first,
                [false, false] => {
                    if top == 0 {
                        return;
                    }
                    top -= 1;
                    stack[top]
                }
            };
        }
    }
}
