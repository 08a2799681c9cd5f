//! Where sub-textures live in the indirection's mip 0: a quadtree (a 2D
//! buddy allocator). Every request is a power-of-two square aligned to its
//! size, the shape a sub-texture of level K needs so that its page squares
//! stay aligned down its mips; a free square is split into four until it
//! fits, and four free siblings merge back. Allocation and freeing take
//! O(log side) steps, and no square is ever moved: a sub-texture that
//! changes level takes a new square and gives back the old (seed 001).

use std::collections::BTreeSet;

/// Free squares per size, by mip-0 offset.
#[derive(Debug, Clone)]
pub struct QuadtreeAllocator {
    /// `free[s]`: free squares of side 2^s.
    free: Vec<BTreeSet<[u32; 2]>>,
    used_texels: u64,
}

impl QuadtreeAllocator {
    pub fn new(side: u32) -> QuadtreeAllocator {
        assert!(side.is_power_of_two());
        let top = side.trailing_zeros() as usize;
        let mut free = vec![BTreeSet::new(); top + 1];
        free[top].insert([0, 0]);
        QuadtreeAllocator { free, used_texels: 0 }
    }

    /// Texels in use.
    pub fn used(&self) -> u64 {
        self.used_texels
    }

    /// An aligned square of side 2^`k`, or `None` when no free square is
    /// large enough.
    pub fn allocate(&mut self, k: u32) -> Option<[u32; 2]> {
        let k = k as usize;
        let s = (k..self.free.len()).find(|&s| !self.free[s].is_empty())?;
        let at = self.free[s].pop_first().expect("non-empty");
        for level in (k..s).rev() {
            // Keep the first quarter, free the other three.
            let h = 1u32 << level;
            for q in [[h, 0], [0, h], [h, h]] {
                self.free[level].insert([at[0] + q[0], at[1] + q[1]]);
            }
        }
        self.used_texels += 1u64 << (2 * k);
        Some(at)
    }

    /// Gives back the square of side 2^`k` at `at` (from `allocate`).
    pub fn free(&mut self, at: [u32; 2], k: u32) {
        let mut k = k as usize;
        let mut at = at;
        self.used_texels -= 1u64 << (2 * k);
        while k + 1 < self.free.len() {
            let parent = at.map(|c| c & !((2u32 << k) - 1));
            let h = 1u32 << k;
            let siblings = [[0, 0], [h, 0], [0, h], [h, h]].map(|q| [parent[0] + q[0], parent[1] + q[1]]);
            let others: Vec<[u32; 2]> = siblings.into_iter().filter(|&b| b != at).collect();
            if !others.iter().all(|b| self.free[k].contains(b)) {
                break;
            }
            for b in &others {
                self.free[k].remove(b);
            }
            at = parent;
            k += 1;
        }
        let fresh = self.free[k].insert(at);
        assert!(fresh, "square {at:?} of side 2^{k} freed twice");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn overlaps(a: ([u32; 2], u32), b: ([u32; 2], u32)) -> bool {
        let (sa, sb) = (1u32 << a.1, 1u32 << b.1);
        a.0[0] < b.0[0] + sb && b.0[0] < a.0[0] + sa && a.0[1] < b.0[1] + sb && b.0[1] < a.0[1] + sa
    }

    #[test]
    fn squares_are_aligned_disjoint_and_merge_back() {
        let mut q = QuadtreeAllocator::new(64);
        let mut held: Vec<([u32; 2], u32)> = Vec::new();
        // A deterministic mix of sizes, freeing every third.
        let mut seed = 12345u32;
        for i in 0..400 {
            seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
            let k = (seed >> 24) % 5;
            if let Some(at) = q.allocate(k) {
                assert!(at.iter().all(|c| c % (1 << k) == 0), "aligned");
                assert!(held.iter().all(|&h| !overlaps(h, (at, k))), "disjoint");
                held.push((at, k));
            }
            if i % 3 == 2 && !held.is_empty() {
                let (at, k) = held.remove((seed as usize >> 8) % held.len());
                q.free(at, k);
            }
            let used: u64 = held.iter().map(|h| 1u64 << (2 * h.1)).sum();
            assert_eq!(q.used(), used);
        }
        for (at, k) in held.drain(..) {
            q.free(at, k);
        }
        assert_eq!(q.used(), 0);
        assert_eq!(q.allocate(6), Some([0, 0]), "everything merged back into one square");
        assert_eq!(q.allocate(0), None, "full");
    }
}
