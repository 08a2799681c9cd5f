//! How large a vertical error looks from a camera: the LOD criterion's
//! projection, shared by streaming (which nodes to load), the traversal's
//! CPU reference and the renderer (its f32 twins are in
//! `traverse_common.glsl` and `lod_select.glsl`).

/// A view that asks for detail: position in world metres, the projection
/// scale in pixels per unit of tangent (`viewport_height / (2 tan(fov_y /
/// 2))`), and the forward axis with the widest angle the frustum opens
/// from it: off the axis a vertical error looks larger (by up to 1 / cos^2
/// of the angle), and the LOD criterion bounds it at the node's worst
/// screen position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraverseCamera {
    pub position_m: [f64; 3],
    pub pixels_per_tan: f64,
    /// Unit forward axis (world).
    pub forward: [f64; 3],
    /// 1 / cos^2 of the widest angle between the forward axis and the
    /// frustum (its corner rays): 1 + tan^2 x + tan^2 y.
    pub widest: f64,
    /// The view frustum's inward planes in world metres (xyz unit normal,
    /// w offset: left, right, bottom, top, near), when the camera draws:
    /// streaming loads what it sees before what it does not.
    pub frustum: Option<[[f64; 4]; 5]>,
}

impl TraverseCamera {
    /// A camera looking along `forward` with a vertical field of view and a
    /// viewport of `size` pixels.
    pub fn perspective(position_m: [f64; 3], forward: [f64; 3], fov_y_deg: f64, size: [u32; 2]) -> Self {
        let tan_y = (fov_y_deg.to_radians() / 2.0).tan();
        let tan_x = tan_y * f64::from(size[0]) / f64::from(size[1]);
        let pixels_per_tan = f64::from(size[1]) / (2.0 * tan_y);
        let widest = 1.0 + tan_x * tan_x + tan_y * tan_y;
        TraverseCamera { position_m, pixels_per_tan, forward, widest, frustum: None }
    }

    /// Whether any of the world-space box [lo, hi] may lie in the frustum
    /// (true without one).
    pub fn sees(&self, lo: [f64; 3], hi: [f64; 3]) -> bool {
        let Some(planes) = &self.frustum else { return true };
        planes.iter().all(|p| {
            // The corner farthest along the inward normal.
            let far: Vec<f64> = (0..3).map(|i| if p[i] >= 0.0 { hi[i] } else { lo[i] }).collect();
            p[0] * far[0] + p[1] * far[1] + p[2] * far[2] + p[3] >= 0.0
        })
    }

    /// Largest projected vertical error (px) of `error_m` anywhere in the
    /// world-space box [lo, hi] (f64; the GPU's f32 test is
    /// `traverse_common.glsl`'s): `error f k / d` with d the box's distance
    /// and k = 1 / cos^2 of its corner farthest off the axis, at most
    /// `widest`.
    pub fn projected_px(&self, error_m: f64, lo: [f64; 3], hi: [f64; 3]) -> f64 {
        let p = self.position_m;
        let o: Vec<f64> = (0..3).map(|i| (lo[i] - p[i]).max(p[i] - hi[i]).max(0.0)).collect();
        let d = (o[0] * o[0] + o[1] * o[1] + o[2] * o[2]).sqrt().max(1e-3);
        let mut k: f64 = 1.0;
        for c in 0..8 {
            let v: Vec<f64> = (0..3).map(|i| if c & (1 << i) != 0 { hi[i] } else { lo[i] } - p[i]).collect();
            let z = v[0] * self.forward[0] + v[1] * self.forward[1] + v[2] * self.forward[2];
            let l2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            k = if z <= 0.0 { self.widest } else { k.max(l2 / (z * z)) };
        }
        error_m * self.pixels_per_tan * k.min(self.widest) / d
    }
}
