//! What this process and the machine spent: CPU time, peak memory, and the time the hypervisor
//! gave to other guests (read from `/proc`; NaN where there is none).

/// CPU time the hypervisor gave to other guests since boot, summed over this machine's cores
/// (`steal` of /proc/stat, in its 100 Hz ticks); NaN where there is no such file (not Linux).
pub(crate) fn steal_seconds() -> f64 {
    std::fs::read_to_string("/proc/stat")
        .ok()
        .and_then(|s| {
            let cpu = s.lines().next()?.split_whitespace().collect::<Vec<_>>();
            (cpu.first() == Some(&"cpu"))
                .then(|| cpu.get(8)?.parse::<f64>().ok())
                .flatten()
        })
        .map_or(f64::NAN, |ticks| ticks / 100.0)
}

/// CPU seconds (user + system, all threads) and peak resident memory (MB) of this process so far,
/// from `/proc` (Linux; NaN elsewhere). CPU time has a 10 ms resolution.
pub(crate) fn process_usage() -> (f64, f64) {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the parenthesised command name; utime and stime are the 12th and 13th.
    let rest = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| {
        f.get(i)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(f64::NAN)
    };
    let cpu = (ticks(11) + ticks(12)) / 100.0;
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let rss = status
        .lines()
        .find(|l| l.starts_with("VmHWM:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0);
    (cpu, rss)
}
