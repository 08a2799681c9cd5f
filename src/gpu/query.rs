//! Timestamp query pools. Results are read without waiting: a pool whose
//! frame has not finished yet reports "not ready" instead of stalling.

use super::context::{Context, Shared};
use super::resources::{inc, Garbage};
use crate::error::{vk_err, Result};
use ash::vk;
use std::sync::Arc;

pub struct TimestampPool {
    pub(crate) raw: vk::QueryPool,
    pub capacity: u32,
    shared: Arc<Shared>,
}

impl TimestampPool {
    pub fn new(ctx: &Context, name: &str, capacity: u32) -> Result<Self> {
        let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(capacity);
        // SAFETY: valid device and create info.
        let raw = unsafe { ctx.shared.device.create_query_pool(&info, None) }.map_err(vk_err("vkCreateQueryPool"))?;
        // SAFETY: hostQueryReset is a required feature; the pool is unused.
        unsafe { ctx.shared.device.reset_query_pool(raw, 0, capacity) };
        inc(&ctx.shared.live.query_pools);
        ctx.set_name(raw, name);
        Ok(TimestampPool { raw, capacity, shared: ctx.shared.clone() })
    }

    /// Raw ticks of queries `0..count`, or `None` if any is not available yet.
    pub fn try_read(&self, count: u32) -> Option<Vec<u64>> {
        assert!(count <= self.capacity);
        let mut data = vec![[0u64; 2]; count as usize];
        // SAFETY: the range is inside the pool; WITH_AVAILABILITY writes a
        // (value, available) pair per query into `data`.
        let r = unsafe {
            self.shared.device.get_query_pool_results(
                self.raw,
                0,
                &mut data,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WITH_AVAILABILITY,
            )
        };
        match r {
            Ok(()) | Err(vk::Result::NOT_READY) if data.iter().all(|d| d[1] != 0) => {
                Some(data.iter().map(|d| d[0]).collect())
            }
            _ => None,
        }
    }
}

impl Drop for TimestampPool {
    fn drop(&mut self) {
        self.shared.retire(Garbage::QueryPool(self.raw));
    }
}
