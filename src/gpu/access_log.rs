//! What a command buffer touched, recorded when asked (tests): each buffer
//! and image, read or written, whole or one array layer, as the recorder's
//! commands name them (descriptor bindings by their reflected access,
//! attachments, copies, transitions, indirect arguments). Two submissions
//! that may run at the same time (a frame's async compute beside the last
//! frame's graphics) must not touch one resource where either writes it.

use ash::vk::Handle;

#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Access {
    /// The Vulkan handle's bits.
    pub object: u64,
    pub name: String,
    pub write: bool,
    /// One array layer, or None: the whole resource.
    pub layer: Option<u32>,
}

impl Access {
    pub(crate) fn new(object: impl Handle, name: &str, write: bool, layer: Option<u32>) -> Self {
        Access { object: object.as_raw(), name: name.to_string(), write, layer }
    }

    /// Both touch the same memory and at least one writes it.
    pub fn conflicts_with(&self, other: &Access) -> bool {
        let layers_meet = match (self.layer, other.layer) {
            (Some(a), Some(b)) => a == b,
            _ => true,
        };
        self.object == other.object && layers_meet && (self.write || other.write)
    }
}

/// Every pair of `a` and `b` in conflict (`Access::conflicts_with`), each
/// pair once.
pub fn conflicts(a: &[Access], b: &[Access]) -> Vec<(Access, Access)> {
    let mut out: Vec<(Access, Access)> =
        a.iter().flat_map(|x| b.iter().filter(|y| x.conflicts_with(y)).map(move |y| (x.clone(), y.clone()))).collect();
    out.sort();
    out.dedup();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn access(object: u64, write: bool, layer: Option<u32>) -> Access {
        Access { object, name: format!("o{object}"), write, layer }
    }

    #[test]
    fn writes_conflict_reads_do_not_and_layers_split_an_image() {
        assert!(access(1, true, None).conflicts_with(&access(1, false, None)));
        assert!(!access(1, false, None).conflicts_with(&access(1, false, None)));
        assert!(!access(1, true, None).conflicts_with(&access(2, true, None)));
        assert!(!access(1, true, Some(3)).conflicts_with(&access(1, true, Some(4))));
        assert!(access(1, true, Some(3)).conflicts_with(&access(1, false, None)));
        let pairs = conflicts(&[access(1, true, None), access(1, true, None)], &[access(1, false, None)]);
        assert_eq!(pairs.len(), 1);
    }
}
