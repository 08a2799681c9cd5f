//! The trees' and bushes' meshes, at unit height (z up, 0 at the ground;
//! an instance scales them by its type's height times its own scale):
//! a conifer (a trunk and a closed cone of a crown) and a bush (a closed
//! ellipsoid), each at three LODs, the last two crossed triangles (tree) or
//! diamonds (bush): the far billboard. All of a mesh lies within 0.56 of
//! (0, 0, 0.45), the sphere `vegetation_cull` tests.

use glam::Vec3;

/// A mesh; `crown[i]`: vertex `i` takes the crown's colour (else the bark's).
#[derive(Debug, Clone, Default)]
pub struct VegMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub crown: Vec<bool>,
    pub indices: Vec<u32>,
}

impl VegMesh {
    fn vertex(&mut self, p: Vec3, n: Vec3, crown: bool) -> u32 {
        self.positions.push(p);
        self.normals.push(n.normalize());
        self.crown.push(crown);
        self.positions.len() as u32 - 1
    }

    /// A ring-by-ring surface of revolution: `rings` (z, radius, normal's
    /// rise over its run) from bottom to top, `sides` around.
    fn revolve(&mut self, rings: &[(f32, f32, f32)], sides: u32, crown: bool) {
        let first = self.positions.len() as u32;
        for &(z, r, rise) in rings {
            for s in 0..sides {
                let a = s as f32 / sides as f32 * std::f32::consts::TAU;
                let (c, sn) = (a.cos(), a.sin());
                self.vertex(Vec3::new(r * c, r * sn, z), Vec3::new(c, sn, rise), crown);
            }
        }
        for k in 0..rings.len() as u32 - 1 {
            for s in 0..sides {
                let (a, b) = (first + k * sides + s, first + k * sides + (s + 1) % sides);
                self.indices.extend([a, b, b + sides, a, b + sides, a + sides]);
            }
        }
    }

    /// A fan closing ring `ring` (its first vertex) at `apex`, facing down
    /// (`down`) or up.
    fn cap(&mut self, ring: u32, sides: u32, apex: Vec3, down: bool, crown: bool) {
        let n = if down { Vec3::NEG_Z } else { Vec3::Z };
        let centre = self.vertex(apex, n, crown);
        for s in 0..sides {
            let (a, b) = (ring + s, ring + (s + 1) % sides);
            self.indices.extend(if down { [b, a, centre] } else { [a, b, centre] });
        }
    }

    /// Two crossed vertical planes, each the polygon `outline` ((x, z)
    /// fanned from its first point), both faces (the draw does not cull).
    fn crossed(&mut self, outline: &[(f32, f32)], crown: bool) {
        for plane in [Vec3::X, Vec3::Y] {
            let across = Vec3::Z.cross(plane);
            let first = self.positions.len() as u32;
            for &(x, z) in outline {
                self.vertex(plane * x + Vec3::Z * z, across + Vec3::Z * 0.8, crown);
            }
            for k in 1..outline.len() as u32 - 1 {
                self.indices.extend([first, first + k, first + k + 1]);
            }
        }
    }
}

/// Trunk radius, crown base and radius of the conifer (unit height).
const TRUNK_R: f32 = 0.03;
const CROWN_BASE: f32 = 0.2;
const CROWN_R: f32 = 0.3;

/// The conifer at `lod` (0..3).
pub fn tree(lod: u32) -> VegMesh {
    let mut m = VegMesh::default();
    if lod == 2 {
        m.crossed(
            &[
                (-TRUNK_R, -0.05),
                (TRUNK_R, -0.05),
                (TRUNK_R, 0.04),
                (TRUNK_R, 0.25),
                (-TRUNK_R, 0.25),
                (-TRUNK_R, 0.04),
            ],
            false,
        );
        m.crossed(&[(-CROWN_R, 0.15), (CROWN_R, 0.15), (0.0, 1.0)], true);
        return m;
    }
    let (trunk_sides, crown_sides, rings) = if lod == 0 { (8, 12, 4) } else { (4, 6, 1) };
    // Rings just above the ground keep the blend into the terrain (its
    // last half metre) off the rest of the trunk.
    let trunk = [(-0.05, TRUNK_R, 0.0), (0.01, TRUNK_R, 0.0), (0.04, TRUNK_R, 0.0), (CROWN_BASE + 0.05, TRUNK_R, 0.0)];
    m.revolve(&trunk, trunk_sides, false);
    // The cone's normal rises by its radius over its height per unit run.
    let rise = CROWN_R / (1.0 - CROWN_BASE);
    let cone: Vec<(f32, f32, f32)> = (0..=rings)
        .map(|k| {
            let t = k as f32 / (rings + 1) as f32;
            (CROWN_BASE + t * (1.0 - CROWN_BASE), CROWN_R * (1.0 - t), rise)
        })
        .collect();
    let base = m.positions.len() as u32;
    m.revolve(&cone, crown_sides, true);
    let top = base + rings * crown_sides;
    m.cap(top, crown_sides, Vec3::Z, false, true);
    m.cap(base, crown_sides, Vec3::Z * CROWN_BASE, true, true);
    m
}

/// The bush's ellipsoid: its centre's height, radius and half height.
const BUSH_C: f32 = 0.45;
const BUSH_R: f32 = 0.55;
const BUSH_H: f32 = 0.5;

/// The top of a mesh at horizontal distance `rho` from its axis, both over
/// the instance's height (what the terrain's sun shadows march over, the
/// canopy): the conifer's cone (its trunk is too thin to cast), the
/// bush's ellipsoid; None beyond them.
pub fn canopy_top(kind: crate::world::vegetation::VegetationKind, rho: f32) -> Option<f32> {
    use crate::world::vegetation::VegetationKind::{Bush, Grass, Tree};
    match kind {
        Tree => (rho <= CROWN_R).then(|| 1.0 - (1.0 - CROWN_BASE) * rho / CROWN_R),
        Bush => (rho <= BUSH_R).then(|| BUSH_C + BUSH_H * (1.0 - (rho / BUSH_R).powi(2)).max(0.0).sqrt()),
        Grass => None,
    }
}

/// The bush at `lod` (0..3): an ellipsoid 1.1 across and 1 high about
/// (0, 0, 0.45).
pub fn bush(lod: u32) -> VegMesh {
    let mut m = VegMesh::default();
    if lod == 2 {
        m.crossed(&[(0.0, BUSH_C - BUSH_H), (BUSH_R, BUSH_C), (0.0, BUSH_C + BUSH_H), (-BUSH_R, BUSH_C)], true);
        return m;
    }
    let (sides, rings) = if lod == 0 { (10, 6) } else { (6, 3) };
    let ring: Vec<(f32, f32, f32)> = (1..rings)
        .map(|k| {
            let phi = -std::f32::consts::FRAC_PI_2 + std::f32::consts::PI * k as f32 / rings as f32;
            let (r, z) = (BUSH_R * phi.cos(), BUSH_C + BUSH_H * phi.sin());
            // An ellipsoid's normal: (x / BUSH_R^2, z / BUSH_H^2) scaled to a unit run.
            (z, r, (phi.sin() / BUSH_H) / (phi.cos() / BUSH_R))
        })
        .collect();
    m.revolve(&ring, sides, true);
    let top = (ring.len() as u32 - 1) * sides;
    m.cap(top, sides, Vec3::new(0.0, 0.0, BUSH_C + BUSH_H), false, true);
    m.cap(0, sides, Vec3::new(0.0, 0.0, BUSH_C - BUSH_H), true, true);
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every mesh lies within the sphere the culling tests, its LOD 0 and 1
    /// closed, and its triangle counts fall with the LOD.
    #[test]
    fn meshes_fit_the_culling_sphere_and_shrink_with_lod() {
        for make in [tree as fn(u32) -> VegMesh, bush] {
            let mut triangles = Vec::new();
            for lod in 0..3 {
                let m = make(lod);
                for p in &m.positions {
                    assert!(p.distance(Vec3::new(0.0, 0.0, 0.45)) <= 0.56, "{p} at LOD {lod}");
                }
                assert_eq!(m.positions.len(), m.normals.len());
                triangles.push(m.indices.len() / 3);
                if lod < 2 {
                    let mut edges = std::collections::HashMap::new();
                    for t in m.indices.chunks_exact(3) {
                        for k in 0..3 {
                            *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
                        }
                    }
                    // The trunk is open at both ends (its foot underground,
                    // its top inside the crown); everything else closed.
                    let open = edges.keys().filter(|(a, b)| !edges.contains_key(&(*b, *a))).count();
                    assert!(open == 0 || open == 2 * if lod == 0 { 8 } else { 4 }, "{open} open edges at LOD {lod}");
                }
            }
            assert!(triangles[0] > triangles[1] && triangles[1] > triangles[2], "{triangles:?}");
        }
    }

    /// The canopy is the meshes' top: no LOD-0 vertex rises above it (the
    /// trunk's excepted), the apex and the rim touch it.
    #[test]
    fn the_canopy_is_the_top_of_the_meshes() {
        use crate::world::vegetation::VegetationKind;
        for (kind, m) in [(VegetationKind::Tree, tree(0)), (VegetationKind::Bush, bush(0))] {
            for (p, crown) in m.positions.iter().zip(&m.crown).filter(|(_, c)| **c) {
                let rho = p.truncate().length();
                let top = canopy_top(kind, rho).unwrap_or_else(|| panic!("{kind:?} {p} outside the canopy ({crown})"));
                assert!(p.z <= top + 1e-5, "{kind:?} vertex {p} above the canopy {top}");
            }
            let apex = m.positions.iter().map(|p| p.z).fold(f32::MIN, f32::max);
            assert!((canopy_top(kind, 0.0).unwrap() - apex).abs() < 1e-6, "{kind:?} apex {apex}");
        }
        assert_eq!(canopy_top(VegetationKind::Tree, CROWN_R + 1e-3), None);
    }
}
