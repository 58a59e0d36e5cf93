//! An obvhs [`Bvh2`] collapsed into a 4-wide tree: a step tests four child boxes in one pass
//! of 4-wide arithmetic, and a ray takes about half the steps of a binary traversal.
//!
//! Each node keeps up to four children, chosen by opening the binary tree from the node down:
//! the inner child with the largest surface is replaced by its two children until there are
//! four (or only leaves). The leaves are the binary tree's, with the same boxes, so a leaf is
//! tested against the same box values as in the binary tree; its ancestors here are a subset of
//! its binary ancestors, and a box that contains another is hit whenever the other is (the slab
//! arithmetic rounds monotonically). So every leaf the binary traversal would test with a hit
//! is tested here, and the closest hit is the same triangle at the same distance unless two
//! triangles tie exactly (then the first found wins, and the order of visits differs from the
//! binary tree's). Empty child slots have every bound at +infinity: their entry distance is
//! +infinity (or a miss), never below the ray's `tmax`.

use glam::{Vec3A, Vec4};
use obvhs::{aabb::Aabb, bvh2::Bvh2, ray::Ray};

// The child record, the splat ray and the stack depth are the pair layout's.
use super::pairs::{Child, Splat, STACK};

/// Four children's boxes, one per lane, per axis; 128 bytes, two cache lines.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Node {
    min: [Vec4; 3],
    max: [Vec4; 3],
    children: [Child; 4],
}

impl Node {
    /// The four children's `Aabb::intersect_ray`: entry distance, or infinity for a miss.
    #[inline(always)]
    fn entries(&self, r: &Splat) -> [f32; 4] {
        let axis = |a: usize| {
            let t1 = (self.min[a] - r.o[a]) * r.inv[a];
            let t2 = (self.max[a] - r.o[a]) * r.inv[a];
            (t1.min(t2), t1.max(t2))
        };
        let (nx, fx) = axis(0);
        let (ny, fy) = axis(1);
        let (nz, fz) = axis(2);
        let near = nx.max(ny).max(nz);
        let far = fx.min(fy).min(fz);
        let hit = far.cmpge(near) & far.cmpge(Vec4::ZERO);
        Vec4::select(hit, near, Vec4::INFINITY).to_array()
    }
}

/// A [`Bvh2`]'s tree collapsed to four children per node (see the module's doc).
#[derive(Clone, Debug)]
pub struct WideBvh {
    root_min: Vec3A,
    root_max: Vec3A,
    /// The root itself when it is a leaf (`count` > 0), else node 0 (`first` = 0).
    root: Child,
    nodes: Vec<Node>,
}

impl WideBvh {
    /// The 4-wide tree of `bvh`, with each leaf's `first` replaced by `leaf(first, count)`
    /// (called once per leaf, depth first); None when empty or too deep for the stack.
    pub fn with_leaves(bvh: &Bvh2, mut leaf: impl FnMut(u32, u32) -> u32) -> Option<Self> {
        let root = bvh.nodes.first()?;
        let mut out = Self {
            root_min: root.aabb().min,
            root_max: root.aabb().max,
            root: Child::default(),
            nodes: Vec::new(),
        };
        if root.is_leaf() {
            out.root = Child {
                first: leaf(root.first_index, root.prim_count),
                count: root.prim_count,
            };
            return Some(out);
        }
        let depth = out.add_node(bvh, 0, &mut leaf);
        (3 * depth <= STACK).then_some(out)
    }

    /// Appends the node for the inner binary node `index` and, depth first, the nodes below;
    /// returns the depth of the subtree in nodes.
    fn add_node(
        &mut self,
        bvh: &Bvh2,
        index: usize,
        leaf: &mut impl FnMut(u32, u32) -> u32,
    ) -> usize {
        let first = bvh.nodes[index].first_index as usize;
        let mut kids = vec![first, first + 1];
        while kids.len() < 4 {
            let open = kids
                .iter()
                .enumerate()
                .filter(|(_, &k)| !bvh.nodes[k].is_leaf())
                .max_by(|a, b| {
                    let area = |k: usize| bvh.nodes[k].aabb().half_area();
                    area(*a.1).total_cmp(&area(*b.1))
                })
                .map(|(at, _)| at);
            let Some(at) = open else { break };
            let left = bvh.nodes[kids[at]].first_index as usize;
            kids[at] = left;
            kids.insert(at + 1, left + 1);
        }
        let at = self.nodes.len();
        let mut node = Node {
            min: [Vec4::INFINITY; 3],
            max: [Vec4::INFINITY; 3],
            children: [Child::default(); 4],
        };
        for (lane, &k) in kids.iter().enumerate() {
            let b: &Aabb = bvh.nodes[k].aabb();
            for axis in 0..3 {
                node.min[axis][lane] = b.min[axis];
                node.max[axis][lane] = b.max[axis];
            }
        }
        self.nodes.push(node);
        let mut depth = 0;
        for (lane, &k) in kids.iter().enumerate() {
            let n = &bvh.nodes[k];
            let child = if n.is_leaf() {
                Child {
                    first: leaf(n.first_index, n.prim_count),
                    count: n.prim_count,
                }
            } else {
                let below = self.nodes.len() as u32;
                depth = depth.max(self.add_node(bvh, k, leaf));
                Child {
                    first: below,
                    count: 0,
                }
            };
            self.nodes[at].children[lane] = child;
        }
        depth + 1
    }

    /// Visits the leaves whose boxes the ray enters before `ray.tmax`, nearer children first:
    /// `leaf(ray, first, count)` tests a leaf's primitives (it may shorten `ray.tmax`) and
    /// returns false to stop; `first` is what [`WideBvh::with_leaves`] stored.
    #[inline(always)]
    pub fn traverse(&self, ray: &mut Ray, mut leaf: impl FnMut(&mut Ray, u32, u32) -> bool) {
        let root = Aabb::new(self.root_min, self.root_max);
        if root.intersect_ray(ray) >= ray.tmax {
            return;
        }
        if self.root.count > 0 {
            leaf(ray, self.root.first, self.root.count);
            return;
        }
        let splat = Splat::new(ray);
        let mut stack = [(0u32, 0f32); STACK];
        let mut top = 0;
        let mut current = 0u32;
        loop {
            let node = &self.nodes[current as usize];
            let t = node.entries(&splat);
            // The children entered before tmax, sorted by entry distance (insertion sort).
            let mut hits = [(0f32, Child::default()); 4];
            let mut n = 0;
            for (k, &tk) in t.iter().enumerate() {
                if tk < ray.tmax {
                    let mut j = n;
                    while j > 0 && hits[j - 1].0 > tk {
                        hits[j] = hits[j - 1];
                        j -= 1;
                    }
                    hits[j] = (tk, node.children[k]);
                    n += 1;
                }
            }
            // Leaves at once (nearest first, each against the tmax the nearer ones left);
            // inner children kept in order: the nearest next, the others pushed.
            let mut inner = [(0u32, 0f32); 4];
            let mut m = 0;
            for &(tk, child) in &hits[..n] {
                if tk >= ray.tmax {
                    break;
                }
                if child.count == 0 {
                    inner[m] = (child.first, tk);
                    m += 1;
                } else if !leaf(ray, child.first, child.count) {
                    return;
                }
            }
            if m > 0 {
                for &entry in inner[1..m].iter().rev() {
                    stack[top] = entry;
                    top += 1;
                }
                current = inner[0].0;
                continue;
            }
            // The next pending node still entered before tmax.
            loop {
                if top == 0 {
                    return;
                }
                top -= 1;
                let (next, tk) = stack[top];
                if tk < ray.tmax {
                    current = next;
                    break;
                }
            }
        }
    }
}
