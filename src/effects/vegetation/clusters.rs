//! The instances in clusters: a grid over the world, each cell's
//! instances contiguous on the GPU with the box around their bounding
//! spheres and the farthest draw distance of their types.
//! `vegetation_cull` tests a cluster first (one workgroup each) and
//! visits its instances only when the cluster may show, so a frame's cost
//! follows what is near the view, not the number of instances (seed 004's
//! grid of vegetation cells, in place of visiting all of them).

use super::{VegetationSet, VegetationTypeGpu};
use crate::world::vegetation::Instance;

/// Most cells along a side: clusters stay within one dispatch's groups.
pub const MAX_SIDE: u32 = 250;

/// Host twin of `VegetationCluster` (vegetation.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VegetationClusterGpu {
    /// xyz: the box's low corner (world m); w: the farthest draw distance.
    pub lo: [f32; 4],
    /// xyz: the box's high corner.
    pub hi: [f32; 4],
    /// Its instances: `count` from `first` of the sorted list.
    pub first: u32,
    pub count: u32,
    pub pad: [u32; 2],
}

/// The instances sorted by cluster and the non-empty clusters.
#[derive(Debug, Clone)]
pub struct Clustered {
    pub instances: Vec<Instance>,
    pub clusters: Vec<VegetationClusterGpu>,
    /// The grid's cell side (m).
    pub cell_m: f32,
}

/// An instance's bounding sphere (centre, radius) with its type's height:
/// the sphere `vegetation_cull` tests (meshes.rs: every LOD within 0.56 of
/// (0, 0, 0.45)).
pub fn sphere(i: &Instance, types: &[VegetationTypeGpu]) -> ([f32; 3], f32) {
    let h = types[i.ty as usize].height_m * i.scale;
    ([i.position[0], i.position[1], i.position[2] + 0.45 * h], 0.56 * h)
}

/// Sorts `set`'s instances into cells of `cell_m` or larger (the grid
/// at most `MAX_SIDE` a side), keeping their order within a cell.
pub fn cluster(set: &VegetationSet, types: &[VegetationTypeGpu], cell_m: f32) -> Clustered {
    let (mut lo, mut hi) = ([f32::MAX; 2], [f32::MIN; 2]);
    for i in &set.instances {
        for a in 0..2 {
            lo[a] = lo[a].min(i.position[a]);
            hi[a] = hi[a].max(i.position[a]);
        }
    }
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(0.0);
    let cell = cell_m.max(span / (MAX_SIDE - 1) as f32);
    let side = [0, 1].map(|a| (((hi[a] - lo[a]).max(0.0) / cell) as u32 + 1).min(MAX_SIDE));
    let key = |i: &Instance| {
        let c = [0, 1].map(|a| (((i.position[a] - lo[a]) / cell) as u32).min(side[a] - 1));
        (c[1] * side[0] + c[0]) as usize
    };
    let mut order: Vec<usize> = (0..set.instances.len()).collect();
    order.sort_by_key(|&k| key(&set.instances[k]));
    let instances: Vec<Instance> = order.iter().map(|&k| set.instances[k]).collect();
    let mut clusters: Vec<VegetationClusterGpu> = Vec::new();
    let mut last = usize::MAX;
    for (n, i) in instances.iter().enumerate() {
        let (c, r) = sphere(i, types);
        let draw = types[i.ty as usize].draw_m;
        if key(i) != last {
            last = key(i);
            let (lo, hi) = ([f32::MAX, f32::MAX, f32::MAX, 0.0], [f32::MIN; 4]);
            clusters.push(VegetationClusterGpu { lo, hi, first: n as u32, count: 0, pad: [0; 2] });
        }
        let k = clusters.last_mut().expect("pushed above");
        for (a, centre) in c.iter().enumerate() {
            k.lo[a] = k.lo[a].min(centre - r);
            k.hi[a] = k.hi[a].max(centre + r);
        }
        k.lo[3] = k.lo[3].max(draw);
        k.count += 1;
    }
    Clustered { instances, clusters, cell_m: cell }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::vegetation::VegetationKind;

    fn one(ty: u32, x: f32, y: f32, scale: f32) -> Instance {
        Instance { position: [x, y, 10.0], yaw_rad: 0.0, scale, ty, tint: 0, cell: 0 }
    }

    /// Every instance once, in its cell's cluster, inside its box; the
    /// box's draw distance its types' farthest; at most MAX_SIDE^2.
    #[test]
    fn every_instance_lies_once_in_its_clusters_box() {
        let types = vec![("spruce".into(), VegetationKind::Tree), ("juniper".into(), VegetationKind::Bush)];
        let instances: Vec<Instance> = (0..5000u32)
            .map(|k| one(k % 2, (k * 7919 % 10_007) as f32, (k * 104_729 % 9_973) as f32, 0.5 + (k % 7) as f32 * 0.1))
            .collect();
        let set = VegetationSet { folder: "t".into(), types, instances };
        let p = super::super::VegetationDrawParams::default();
        let gpu = p.types_gpu(&set);
        let c = cluster(&set, &gpu, 64.0);
        assert!(c.cell_m > 40.0 && c.clusters.len() <= (MAX_SIDE * MAX_SIDE) as usize, "{} m", c.cell_m);
        assert_eq!(c.clusters.iter().map(|k| k.count).sum::<u32>(), 5000);
        let mut seen: Vec<u32> = Vec::new();
        for k in &c.clusters {
            let members = &c.instances[k.first as usize..(k.first + k.count) as usize];
            for a in 0..2 {
                let (lo, hi) =
                    members.iter().fold((f32::MAX, f32::MIN), |(l, h), i| (l.min(i.position[a]), h.max(i.position[a])));
                assert!(hi - lo < c.cell_m, "one cell a cluster: {lo}..{hi}");
            }
            for i in members {
                let (s, r) = sphere(i, &gpu);
                assert!((0..3).all(|a| k.lo[a] <= s[a] - r && s[a] + r <= k.hi[a]), "{i:?} outside {k:?}");
                assert!(k.lo[3] >= gpu[i.ty as usize].draw_m);
                seen.push(i.position[0].to_bits() ^ i.position[1].to_bits().rotate_left(7) ^ i.ty);
            }
        }
        let mut want: Vec<u32> = set
            .instances
            .iter()
            .map(|i| i.position[0].to_bits() ^ i.position[1].to_bits().rotate_left(7) ^ i.ty)
            .collect();
        seen.sort_unstable();
        want.sort_unstable();
        assert_eq!(seen, want);
    }
}
