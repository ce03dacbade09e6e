//! GPU timing through named scopes: timestamps and pipeline statistics side by side.
//!
//! A scope opens with a debug label, a timestamp and a pipeline-statistics query, and closes with
//! a bottom-of-pipe timestamp. Ticks are masked with the queue's `timestampValidBits` and scaled
//! by `timestampPeriod` into [`Nanos`]. Scopes don't nest: a pipeline-statistics query can't be
//! active twice in a command buffer, so opening a second one is a typed error rather than a
//! validation message. Scopes wrap whole passes (outside rendering scopes).
//!
//! Each timestamp is followed by a full execution barrier, and the opening one waits for all
//! prior commands (`ALL_COMMANDS`, not top-of-pipe). On a GPU this isolates the measured pass
//! from the work around it. On lavapipe it is what makes the numbers mean anything: llvmpipe
//! bins a timestamp into its current tiled scene and stamps it when the rasterizer reaches it in
//! each tile, so a timestamp sharing a scene with draws reads "when the last tile got here".
//! The barrier flushes the scene, leaving each timestamp alone in its own scene, stamped when
//! all earlier work has been rasterized.

use std::sync::Arc;

use ash::vk;

use super::command::Recorder;
use super::device::Device;
use super::error::{Check, VkError, VkResult};

/// A duration in nanoseconds measured by the GPU.
#[derive(Clone, Copy, Debug, Default, PartialEq, PartialOrd)]
pub struct Nanos(pub f64);

impl Nanos {
    pub fn as_ms(self) -> f64 {
        self.0 * 1e-6
    }

    /// Nanoseconds between two raw tick values, honouring the valid-bit mask (a counter that
    /// wrapped between the two reads still gives the right distance).
    pub fn from_ticks(begin: u64, end: u64, valid_bits: u32, period_ns: f32) -> Self {
        let mask = if valid_bits >= 64 {
            u64::MAX
        } else {
            (1u64 << valid_bits) - 1
        };
        let ticks = (end & mask).wrapping_sub(begin & mask) & mask;
        Self(ticks as f64 * period_ns as f64)
    }
}

/// What one scope measured.
#[derive(Clone, Debug, PartialEq)]
pub struct ScopeTiming {
    pub name: String,
    pub begin_ticks: u64,
    pub end_ticks: u64,
    pub duration: Nanos,
    /// `None` when the device has no pipeline-statistics queries.
    pub vertex_invocations: Option<u64>,
    pub fragment_invocations: Option<u64>,
    pub compute_invocations: Option<u64>,
}

/// Proof that a scope is open; hand it back to [`GpuProfiler::end`].
#[must_use = "close the scope with GpuProfiler::end"]
pub struct ScopeToken(u32);

/// Errors of scope misuse.
#[derive(Debug, thiserror::Error)]
pub enum ScopeError {
    #[error("scope `{0}` is still open; scopes do not nest")]
    AlreadyOpen(String),
    #[error("all {0} scopes of this profiler are used; reset it first")]
    Full(u32),
    #[error("{0} scope(s) were never closed")]
    Unclosed(u32),
}

const STATISTICS: vk::QueryPipelineStatisticFlags = vk::QueryPipelineStatisticFlags::from_raw(
    vk::QueryPipelineStatisticFlags::VERTEX_SHADER_INVOCATIONS.as_raw()
        | vk::QueryPipelineStatisticFlags::FRAGMENT_SHADER_INVOCATIONS.as_raw()
        | vk::QueryPipelineStatisticFlags::COMPUTE_SHADER_INVOCATIONS.as_raw(),
);

pub struct GpuProfiler {
    device: Arc<Device>,
    timestamps: vk::QueryPool,
    statistics: Option<vk::QueryPool>,
    capacity: u32,
    names: Vec<String>,
    open: Option<u32>,
}

impl GpuProfiler {
    pub fn new(device: &Arc<Device>, capacity: u32, name: &str) -> VkResult<Self> {
        if !device.report.timestamps {
            return Err(VkError::NoTimestamps(device.queue_family));
        }
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(capacity * 2);
        // SAFETY: valid create info on a live device.
        let timestamps =
            unsafe { device.raw.create_query_pool(&info, None) }.check("vkCreateQueryPool")?;
        device.set_name(timestamps, &format!("{name} timestamps"));
        let mut profiler = Self {
            device: device.clone(),
            timestamps,
            statistics: None,
            capacity,
            names: Vec::new(),
            open: None,
        };
        if device.report.pipeline_statistics {
            let info = vk::QueryPoolCreateInfo::default()
                .query_type(vk::QueryType::PIPELINE_STATISTICS)
                .query_count(capacity)
                .pipeline_statistics(STATISTICS);
            // SAFETY: the feature was enabled at device creation.
            let pool =
                unsafe { device.raw.create_query_pool(&info, None) }.check("vkCreateQueryPool")?;
            device.set_name(pool, &format!("{name} statistics"));
            profiler.statistics = Some(pool);
        }
        profiler.reset();
        Ok(profiler)
    }

    /// Forgets all scopes and resets the queries from the host (no GPU work may be pending on
    /// them: call after the previous submission was waited for).
    pub fn reset(&mut self) {
        // SAFETY: host query reset was enabled at device creation; callers reset only when no
        // submission using the pools is pending.
        unsafe {
            self.device
                .raw
                .reset_query_pool(self.timestamps, 0, self.capacity * 2);
            if let Some(pool) = self.statistics {
                self.device.raw.reset_query_pool(pool, 0, self.capacity);
            }
        }
        self.names.clear();
        self.open = None;
    }

    pub fn begin(&mut self, rec: &mut Recorder<'_>, name: &str) -> Result<ScopeToken, ScopeError> {
        if let Some(open) = self.open {
            return Err(ScopeError::AlreadyOpen(self.names[open as usize].clone()));
        }
        let index = self.names.len() as u32;
        if index >= self.capacity {
            return Err(ScopeError::Full(self.capacity));
        }
        self.names.push(name.to_owned());
        self.open = Some(index);
        rec.begin_label(name);
        // SAFETY: recording state; the queries were reset and are written once.
        unsafe {
            self.device.raw.cmd_write_timestamp2(
                rec.raw,
                vk::PipelineStageFlags2::ALL_COMMANDS,
                self.timestamps,
                index * 2,
            );
            drain(&self.device, rec);
            if let Some(pool) = self.statistics {
                self.device.raw.cmd_begin_query(
                    rec.raw,
                    pool,
                    index,
                    vk::QueryControlFlags::empty(),
                );
            }
        }
        Ok(ScopeToken(index))
    }

    pub fn end(&mut self, rec: &mut Recorder<'_>, token: ScopeToken) {
        let index = token.0;
        // SAFETY: paired with `begin` in the same command buffer (the token proves it).
        unsafe {
            if let Some(pool) = self.statistics {
                self.device.raw.cmd_end_query(rec.raw, pool, index);
            }
            self.device.raw.cmd_write_timestamp2(
                rec.raw,
                vk::PipelineStageFlags2::BOTTOM_OF_PIPE,
                self.timestamps,
                index * 2 + 1,
            );
            drain(&self.device, rec);
        }
        rec.end_label();
        self.open = None;
    }

    /// Results of every scope, waiting for them if necessary. Call after the submission that
    /// recorded them.
    pub fn results(&self) -> VkResult<Vec<ScopeTiming>> {
        if self.open.is_some() {
            return Err(VkError::Unsupported(ScopeError::Unclosed(1).to_string()));
        }
        let count = self.names.len() as u32;
        if count == 0 {
            return Ok(Vec::new());
        }
        let mut ticks = vec![0u64; count as usize * 2];
        // SAFETY: every query in range was written by a completed submission.
        unsafe {
            self.device.raw.get_query_pool_results(
                self.timestamps,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .check("vkGetQueryPoolResults(timestamps)")?;
        let mut stats = vec![[0u64; 3]; count as usize];
        if let Some(pool) = self.statistics {
            // SAFETY: as above.
            unsafe {
                self.device.raw.get_query_pool_results(
                    pool,
                    0,
                    &mut stats,
                    vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                )
            }
            .check("vkGetQueryPoolResults(statistics)")?;
        }
        let report = &self.device.report;
        let has_stats = self.statistics.is_some();
        Ok(self
            .names
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let (begin, end) = (ticks[2 * i], ticks[2 * i + 1]);
                ScopeTiming {
                    name: name.clone(),
                    begin_ticks: begin,
                    end_ticks: end,
                    duration: Nanos::from_ticks(
                        begin,
                        end,
                        report.timestamp_valid_bits,
                        report.timestamp_period_ns,
                    ),
                    vertex_invocations: has_stats.then_some(stats[i][0]),
                    fragment_invocations: has_stats.then_some(stats[i][1]),
                    compute_invocations: has_stats.then_some(stats[i][2]),
                }
            })
            .collect())
    }
}

/// A full execution barrier.
fn drain(device: &Device, rec: &Recorder<'_>) {
    let barrier = [vk::MemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
    let info = vk::DependencyInfo::default().memory_barriers(&barrier);
    // SAFETY: recording state, outside a rendering scope (scopes wrap whole passes).
    unsafe { device.raw.cmd_pipeline_barrier2(rec.raw, &info) };
}

impl Drop for GpuProfiler {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        // SAFETY: module invariant: no pending GPU work writes the pools.
        unsafe {
            self.device.raw.destroy_query_pool(self.timestamps, None);
            if let Some(pool) = self.statistics {
                self.device.raw.destroy_query_pool(pool, None);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Nanos;

    #[test]
    fn ticks_are_masked_and_scaled() {
        assert_eq!(Nanos::from_ticks(10, 30, 64, 1.0).0, 20.0);
        assert_eq!(Nanos::from_ticks(10, 30, 64, 2.5).0, 50.0);
        // A 36-bit counter that wrapped between the reads.
        let max = (1u64 << 36) - 1;
        assert_eq!(Nanos::from_ticks(max - 4, 5, 36, 1.0).0, 10.0);
        // Bits above the valid range are ignored.
        assert_eq!(Nanos::from_ticks(1 << 40, (1 << 40) | 7, 36, 1.0).0, 7.0);
    }
}
