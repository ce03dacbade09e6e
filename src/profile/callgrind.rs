//! Callgrind client requests: the program tells valgrind where the measured region starts and
//! ends, so only the shaded draw is instrumented (`valgrind --instr-atstart=no`).
//!
//! The protocol (valgrind.h, callgrind.h): a marker sequence of four `rol`s of `rdi` by 128 bits
//! in all (a no-op on the real CPU) followed by `xchg rbx, rbx`; valgrind recognises it, reads
//! the request's six words from the array `rax` points at and returns the answer in `rdx`.
//! Outside valgrind the sequence does nothing and `rdx` keeps the default, so every request is
//! safe to issue natively.

use std::ffi::CStr;

/// `VG_USERREQ_TOOL_BASE('C','T')`: callgrind's request numbers follow it in this order.
const CALLGRIND_BASE: u64 = ((b'C' as u64) << 24) | ((b'T' as u64) << 16);
const DUMP_STATS_AT: u64 = CALLGRIND_BASE + 3;
const START_INSTRUMENTATION: u64 = CALLGRIND_BASE + 4;
const STOP_INSTRUMENTATION: u64 = CALLGRIND_BASE + 5;
/// valgrind core: answers the number of valgrind layers the program runs under (0 natively).
const RUNNING_ON_VALGRIND: u64 = 0x1001;

#[cfg(target_arch = "x86_64")]
fn request(default: u64, code: u64, arg1: u64) -> u64 {
    let args: [u64; 6] = [code, arg1, 0, 0, 0, 0];
    let result;
    // SAFETY: the rotations leave `rdi` as it was (3 + 13 + 61 + 51 = 128 bits) and it is
    // declared clobbered anyway; `xchg rbx, rbx` changes nothing; valgrind only reads `args`
    // (alive for the whole asm block) and writes `rdx`, declared as the output. Natively the
    // block is a no-op that returns `default`.
    unsafe {
        std::arch::asm!(
            "rol rdi, 3",
            "rol rdi, 13",
            "rol rdi, 61",
            "rol rdi, 51",
            "xchg rbx, rbx",
            inout("rdx") default => result,
            in("rax") args.as_ptr(),
            inout("rdi") 0u64 => _,
            options(nostack),
        );
    }
    result
}

#[cfg(not(target_arch = "x86_64"))]
fn request(default: u64, _code: u64, _arg1: u64) -> u64 {
    default
}

/// Whether this process runs under valgrind (always false off x86_64, where lamina does not
/// implement the requests).
pub fn running() -> bool {
    request(0, RUNNING_ON_VALGRIND, 0) > 0
}

pub fn start_instrumentation() {
    request(0, START_INSTRUMENTATION, 0);
}

pub fn stop_instrumentation() {
    request(0, STOP_INSTRUMENTATION, 0);
}

/// Writes the counts gathered since the last dump into a new file whose `desc:` line carries
/// `name`, and zeroes them.
pub fn dump_stats_at(name: &CStr) {
    request(0, DUMP_STATS_AT, name.as_ptr() as u64);
}

#[cfg(test)]
mod tests {
    #[test]
    fn requests_are_no_ops_natively() {
        // The test harness does not run under valgrind: every request answers its default.
        assert!(!super::running());
        super::start_instrumentation();
        super::stop_instrumentation();
        super::dump_stats_at(c"native");
    }
}
