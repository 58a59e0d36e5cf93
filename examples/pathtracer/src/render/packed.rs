//! A mesh's fast ray queries: its obvhs [`Bvh2`] collapsed to a 4-wide tree ([`WideBvh`]) and
//! each leaf's triangles packed four to a [`TriLanes`]. Every answer is obvhs's, bit for bit,
//! up to exact ties between two triangles' distances (tested against it in `geometry`'s
//! tests).

use glam::{Vec3A, Vec4};
use obvhs::{bvh2::Bvh2, ray::Ray};

use super::tri_lanes::{RayLanes, TriLanes};
use super::wide::WideBvh;

/// The trees and packed triangles of one mesh; a leaf's `first` is its first pack.
pub struct PackedMesh {
    tree: WideBvh,
    packs: Vec<TriLanes>,
}

impl PackedMesh {
    /// From `bvh` and its triangles in its primitive order, each as (v0, e1, e2, e1 x e2) of
    /// obvhs's Möller-Trumbore test; None when the 4-wide layout does not take the tree.
    pub fn new(bvh: &Bvh2, tris: &[[Vec3A; 4]]) -> Option<Self> {
        let mut packs = Vec::new();
        let tree = WideBvh::with_leaves(bvh, |first, count| {
            let at = packs.len() as u32;
            let leaf = &tris[first as usize..(first + count) as usize];
            for (k, four) in leaf.chunks(4).enumerate() {
                packs.push(TriLanes::pack(first + 4 * k as u32, four));
            }
            at
        })?;
        Some(Self { tree, packs })
    }

    /// The packs of a leaf whose first pack is `first` and which holds `count` triangles.
    #[inline(always)]
    fn leaf(&self, first: u32, count: u32) -> &[TriLanes] {
        &self.packs[first as usize..(first + count.div_ceil(4)) as usize]
    }

    /// Closest (distance, triangle) as obvhs's `Bvh2::ray_traverse`: each lane that hits
    /// closer than the closest so far replaces it, in the leaf's order, as obvhs's loop does.
    #[inline(always)]
    pub fn closest(&self, mut ray: Ray) -> Option<(f32, u32)> {
        let lanes = RayLanes::new(ray.origin, ray.direction);
        let mut found = None;
        self.tree.traverse(&mut ray, |ray, first, count| {
            for pack in self.leaf(first, count) {
                let (t, mut hits) = pack.distances(&lanes, ray.tmin);
                while hits != 0 {
                    let k = hits.trailing_zeros();
                    hits &= hits - 1;
                    if t[k as usize] < ray.tmax {
                        ray.tmax = t[k as usize];
                        found = Some(pack.first() + k);
                    }
                }
            }
            true
        });
        found.map(|id| (ray.tmax, id))
    }

    /// Whether a triangle lies on the ray before `ray.tmax`, as obvhs's
    /// `Bvh2::ray_traverse_miss` (negated).
    #[inline(always)]
    pub fn any(&self, mut ray: Ray) -> bool {
        let lanes = RayLanes::new(ray.origin, ray.direction);
        let mut hit = false;
        self.tree.traverse(&mut ray, |ray, first, count| {
            for pack in self.leaf(first, count) {
                let (t, hits) = pack.distances(&lanes, ray.tmin);
                let before = Vec4::from_array(t).cmplt(Vec4::splat(ray.tmax)).bitmask();
                if hits & before != 0 {
                    hit = true;
                    return false;
                }
            }
            true
        });
        hit
    }
}
