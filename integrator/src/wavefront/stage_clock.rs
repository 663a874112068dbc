//! The stages' clock ([`StageClock`]): read twice for every stage a tile runs when stages are
//! timed (`--stats`, `--aov time`, traces), so it must cost little. `Instant::now` goes through
//! `clock_gettime` in the vDSO, about 1.2% of cornell's profile with `--aov time`; the CPU's
//! time-stamp counter (`rdtsc`) is read in a few cycles. Counter ticks become seconds per tile,
//! by the tile's own wall time (an `Instant` at each end), so no start-up calibration is
//! needed, as the `quanta` and `minstant` crates do for a clock of absolute times. The counter
//! is used only where the CPU says it is invariant (CPUID leaf 0x8000_0007, EDX bit 8: one rate
//! in every power state, as on x86-64 CPUs of the last decade and the VMs that pass the bit
//! on); elsewhere the ticks are nanoseconds of `Instant`.

#![cfg_attr(target_arch = "x86_64", expect(unsafe_code, reason = "reads the time-stamp counter"))]

use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// A cheap clock of the stages, in ticks; [`StageClock::span`] and [`Span::to_duration`] turn
/// ticks into time.
#[derive(Clone, Copy, Debug)]
pub(super) struct StageClock {
    /// Whether ticks are the time-stamp counter's (else nanoseconds since `epoch`).
    counter: bool,
    epoch: Instant,
}

impl StageClock {
    /// The process's stage clock (the CPU is asked once).
    pub(super) fn get() -> Self {
        static CLOCK: OnceLock<StageClock> = OnceLock::new();
        *CLOCK.get_or_init(|| Self { counter: invariant_counter(), epoch: Instant::now() })
    }

    /// The clock's reading now, in ticks.
    #[inline(always)]
    pub(super) fn now(self) -> u64 {
        #[cfg(target_arch = "x86_64")]
        if self.counter {
            // SAFETY: `rdtsc` exists on every x86-64 CPU and reads a register, nothing else.
            return unsafe { core::arch::x86_64::_rdtsc() };
        }
        self.epoch.elapsed().as_nanos() as u64
    }

    /// Starts a span over which ticks are converted to time: its ends are read on both clocks.
    pub(super) fn span(self) -> Span {
        Span { clock: self, wall: Instant::now(), ticks: self.now() }
    }
}

/// The start of a stretch of work whose ticks become time by its wall time
/// ([`Span::to_duration`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Span {
    clock: StageClock,
    wall: Instant,
    ticks: u64,
}

impl Span {
    /// A function from ticks counted since the span began to their time, by the wall time
    /// and the ticks that have passed since (zero for a span without ticks).
    pub(super) fn to_duration(self) -> impl Fn(u64) -> Duration {
        let (wall, ticks) = (self.wall.elapsed().as_secs_f64(), self.clock.now().wrapping_sub(self.ticks));
        let per_tick = if ticks > 0 { wall / ticks as f64 } else { 0.0 };
        move |t| Duration::from_secs_f64(t as f64 * per_tick)
    }
}

/// Whether the CPU's time-stamp counter runs at one rate in every power state.
fn invariant_counter() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        use core::arch::x86_64::__cpuid;
        const LEAF: u32 = 0x8000_0007;
        if __cpuid(0x8000_0000).eax >= LEAF {
            return __cpuid(LEAF).edx & (1 << 8) != 0;
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ticks over a sleep come out as about the sleep's time, whichever clock counts them.
    #[test]
    fn ticks_become_the_time_that_passed() {
        for clock in [StageClock::get(), StageClock { counter: false, epoch: Instant::now() }] {
            let span = clock.span();
            let start = clock.now();
            std::thread::sleep(Duration::from_millis(30));
            let ticks = clock.now() - start;
            let secs = span.to_duration()(ticks).as_secs_f64();
            assert!((0.029..0.5).contains(&secs), "{clock:?}: {secs} s for a 30 ms sleep");
        }
    }
}
