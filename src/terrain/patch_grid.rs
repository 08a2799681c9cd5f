//! Index pattern of a terrain patch: an n x n quad grid whose quads are split
//! along alternating diagonals so that every vertex with odd/odd grid
//! coordinates is the centre of 8 triangles (the diamond pattern). A hole
//! vertex (NaN position) then removes exactly those 8 triangles.

/// Counter-clockwise triangles (seen from +z) of an n x n quad grid with
/// (n+1)^2 vertices in row-major order.
pub fn diamond_indices(n: u32) -> Vec<u32> {
    assert!(n >= 1 && n.is_multiple_of(2), "diamond pattern needs an even quad count, got {n}");
    let v = |x: u32, y: u32| y * (n + 1) + x;
    let mut out = Vec::with_capacity((n * n * 6) as usize);
    for y in 0..n {
        for x in 0..n {
            let (a, b, c, d) = (v(x, y), v(x + 1, y), v(x + 1, y + 1), v(x, y + 1));
            // The diagonal must touch the quad's odd/odd corner: it runs
            // a-c when that corner is a or c, b-d otherwise.
            if (x % 2) == (y % 2) {
                out.extend_from_slice(&[a, b, c, a, c, d]);
            } else {
                out.extend_from_slice(&[a, b, d, b, c, d]);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn odd_odd_vertices_touch_eight_triangles() {
        let n = 16;
        let idx = diamond_indices(n);
        for y in 1..n {
            for x in 1..n {
                let touching = idx.chunks(3).filter(|t| t.contains(&(y * (n + 1) + x))).count();
                let expect = if x % 2 == y % 2 { 8 } else { 4 };
                assert_eq!(touching, expect, "vertex ({x},{y})");
            }
        }
    }
}
