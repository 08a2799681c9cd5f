//! Timestamp and pipeline statistics query pools. Results are read
//! without waiting: a pool whose frame has not finished yet reports "not
//! ready" instead of stalling.

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

/// The counters a statistics query collects, in the order results come
/// back (Vulkan orders them by their flag bits).
pub const STATISTICS: [vk::QueryPipelineStatisticFlags; 5] = [
    vk::QueryPipelineStatisticFlags::INPUT_ASSEMBLY_PRIMITIVES,
    vk::QueryPipelineStatisticFlags::VERTEX_SHADER_INVOCATIONS,
    vk::QueryPipelineStatisticFlags::CLIPPING_PRIMITIVES,
    vk::QueryPipelineStatisticFlags::FRAGMENT_SHADER_INVOCATIONS,
    vk::QueryPipelineStatisticFlags::COMPUTE_SHADER_INVOCATIONS,
];

/// Pipeline statistics queries of the [`STATISTICS`] counters. Their
/// graphics counters make them legal only on a graphics queue.
pub struct StatisticsPool {
    pub(crate) raw: vk::QueryPool,
    pub capacity: u32,
    shared: Arc<Shared>,
}

impl StatisticsPool {
    /// Needs `Limits::pipeline_statistics` (the device feature enabled).
    pub fn new(ctx: &Context, name: &str, capacity: u32) -> Result<Self> {
        assert!(ctx.info().limits.pipeline_statistics, "pipeline statistics queries are not enabled on this device");
        let flags = STATISTICS.iter().fold(vk::QueryPipelineStatisticFlags::empty(), |a, f| a | *f);
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::PIPELINE_STATISTICS)
            .query_count(capacity)
            .pipeline_statistics(flags);
        // SAFETY: valid device and create info; the feature was enabled (asserted).
        let raw = unsafe { ctx.shared.device.create_query_pool(&info, None) }.map_err(vk_err("vkCreateQueryPool"))?;
        // SAFETY: hostQueryReset is a required feature; the pool is unused.
        unsafe { ctx.shared.device.reset_query_pool(raw, 0, capacity) };
        inc(&ctx.shared.live.query_pools);
        ctx.set_name(raw, name);
        Ok(StatisticsPool { raw, capacity, shared: ctx.shared.clone() })
    }

    /// The counters of queries `0..count` ([`STATISTICS`] order), each
    /// `None` while not available (or never begun this frame).
    pub fn try_read(&self, count: u32) -> Vec<Option<[u64; 5]>> {
        assert!(count <= self.capacity);
        let mut data = vec![[0u64; 6]; count as usize];
        // SAFETY: the range is inside the pool; WITH_AVAILABILITY writes the
        // five counters and then the availability word per query.
        let r = unsafe {
            self.shared.device.get_query_pool_results(
                self.raw,
                0,
                &mut data,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WITH_AVAILABILITY,
            )
        };
        let ok = matches!(r, Ok(()) | Err(vk::Result::NOT_READY));
        data.iter().map(|d| (ok && d[5] != 0).then_some([d[0], d[1], d[2], d[3], d[4]])).collect()
    }
}

impl Drop for StatisticsPool {
    fn drop(&mut self) {
        self.shared.retire(Garbage::QueryPool(self.raw));
    }
}

impl Drop for TimestampPool {
    fn drop(&mut self) {
        self.shared.retire(Garbage::QueryPool(self.raw));
    }
}
