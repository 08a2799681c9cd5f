//! What frame N+1's compute rewrites while frame N's graphics still reads
//! it: one copy per frame parity. With a compute-only queue (async
//! compute) frame N+1's traversal and culling run beside frame N's draws,
//! so the node list, LOD map, sector data, patch selection, patch lists,
//! view constants, node texture and visibility bits of the two frames
//! live in different copies; frame N+2's compute waits only for frame N's
//! graphics ([`COMPUTE_LAG`]). One queue runs the same scheme.

pub use crate::gpu::{COMPUTE_LAG, FRAME_COPIES as COPIES};

/// One `T` per frame parity; `current` is the recorded frame's.
pub struct PerFrame<T> {
    copies: [T; COPIES],
    current: usize,
}

impl<T> PerFrame<T> {
    /// `make(i)` makes copy `i` (named `…[i]` by the caller).
    pub fn new<E>(mut make: impl FnMut(usize) -> Result<T, E>) -> Result<Self, E> {
        Ok(PerFrame { copies: [make(0)?, make(1)?], current: 0 })
    }

    /// Frame `frame` (numbers grow by one per recorded frame) uses its
    /// parity's copy from now on.
    pub fn select(&mut self, frame: u64) {
        self.current = (frame % COPIES as u64) as usize;
    }

    /// The copy of the frame being (or last) recorded.
    pub fn current(&self) -> &T {
        &self.copies[self.current]
    }

    pub fn current_mut(&mut self) -> &mut T {
        &mut self.copies[self.current]
    }

    /// Both copies (memory reports, initialisation).
    pub fn all(&self) -> &[T; COPIES] {
        &self.copies
    }
}

/// The name of copy `i` of a resource.
pub fn copy_name(name: &str, i: usize) -> String {
    format!("{name}[{i}]")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_alternate_between_the_copies() {
        let mut p = PerFrame::new(|i| Ok::<_, ()>(i * 10)).unwrap();
        p.select(1);
        assert_eq!(*p.current(), 10);
        p.select(2);
        assert_eq!(*p.current(), 0);
        p.select(3);
        assert_eq!(*p.current(), 10);
        assert_eq!(p.all(), &[0, 10]);
    }
}
