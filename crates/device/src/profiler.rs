//! Named GPU timestamp scopes: a begin/end timestamp pair around each stage of a command buffer.

use std::cell::{Cell, RefCell};

use anyhow::{bail, Context as _, Result};
use ash::vk;

use crate::context::Context;

/// One scope's GPU time.
#[derive(Clone, Debug, PartialEq)]
pub struct ScopeTiming {
    pub name: &'static str,
    /// Start on the device's timestamp clock, in milliseconds (comparable across command buffers of one
    /// device; its origin is the device's).
    pub start_ms: f64,
    pub duration_ms: f64,
}

/// A timestamp query pool that hands out begin/end pairs by name.
pub struct Profiler {
    ctx: Context,
    pool: vk::QueryPool,
    capacity: u32,
    // Interior mutability: scopes are opened while the command buffer's other state is borrowed.
    scopes: RefCell<Vec<(&'static str, u32)>>,
    next: Cell<u32>,
}

impl Profiler {
    /// A pool for up to `max_scopes` scopes per command buffer.
    pub fn new(ctx: &Context, max_scopes: u32) -> Result<Profiler> {
        let capacity = max_scopes * 2;
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(capacity);
        let pool = unsafe { ctx.device().create_query_pool(&info, None) }.context("creating a timestamp query pool")?;
        ctx.name_object(pool, "profiler timestamps");
        unsafe { ctx.device().reset_query_pool(pool, 0, capacity) };
        Ok(Profiler {
            ctx: ctx.clone(),
            pool,
            capacity,
            scopes: RefCell::new(Vec::new()),
            next: Cell::new(0),
        })
    }

    /// Forgets the previous command buffer's scopes (host-side reset; call before recording).
    pub fn reset(&self) {
        unsafe { self.ctx.device().reset_query_pool(self.pool, 0, self.capacity) };
        self.scopes.borrow_mut().clear();
        self.next.set(0);
    }

    /// Records `body` between two timestamps named `name`.
    pub fn scope<T>(&self, cmd: vk::CommandBuffer, name: &'static str, body: impl FnOnce() -> Result<T>) -> Result<T> {
        let first = self.next.get();
        if first + 2 > self.capacity {
            bail!("timestamp pool full ({} scopes): raise max_scopes", self.capacity / 2);
        }
        self.next.set(first + 2);
        let device = self.ctx.device();
        unsafe { device.cmd_write_timestamp(cmd, vk::PipelineStageFlags::TOP_OF_PIPE, self.pool, first) };
        let value = body()?;
        unsafe { device.cmd_write_timestamp(cmd, vk::PipelineStageFlags::BOTTOM_OF_PIPE, self.pool, first + 1) };
        self.scopes.borrow_mut().push((name, first));
        Ok(value)
    }

    /// Reads the scopes of the last submitted command buffer (it must have completed).
    pub fn read(&self) -> Result<Vec<ScopeTiming>> {
        let next = self.next.get();
        if next == 0 {
            return Ok(Vec::new());
        }
        let mut ticks = vec![0u64; next as usize];
        unsafe {
            self.ctx.device().get_query_pool_results(
                self.pool,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .context("reading timestamp queries")?;
        let bits = self.ctx.timestamp_valid_bits();
        let mask = if bits >= 64 { u64::MAX } else { (1u64 << bits) - 1 };
        let period_ms = self.ctx.timestamp_period() * 1e-6;
        Ok(self
            .scopes
            .borrow()
            .iter()
            .map(|&(name, i)| {
                let a = ticks[i as usize] & mask;
                let b = ticks[i as usize + 1] & mask;
                ScopeTiming {
                    name,
                    start_ms: a as f64 * period_ms,
                    duration_ms: b.wrapping_sub(a) as f64 * period_ms,
                }
            })
            .collect())
    }
}

impl Drop for Profiler {
    fn drop(&mut self) {
        unsafe { self.ctx.device().destroy_query_pool(self.pool, None) };
    }
}
