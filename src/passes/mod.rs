//! One pass per file; the pass, its shader and its timer label share a name.

pub mod diamond_patch;
pub mod prefix_sum;
pub mod quadtree_update;
pub mod smoke_triangle;
pub mod traverse;
