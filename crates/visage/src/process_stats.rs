//! CPU time and peak memory of this process, from Linux's `/proc/self` (std only; elsewhere the
//! figures are absent). The CPU time counts the child processes that have ended and been waited
//! for — the FFmpeg decoder, once its video is read to the end or closed — so a run's CPU is the
//! whole job's, decoding included.

/// Clock ticks per second of `/proc/self/stat`'s CPU times (`sysconf(_SC_CLK_TCK)`, 100 on
/// every Linux architecture visage targets).
const CLOCK_TICKS_PER_SECOND: f64 = 100.0;

/// User + system CPU seconds used so far by this process (all threads) and by its children
/// that have ended and been waited for.
pub fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (which may hold spaces) start at field 3 (state);
    // utime, stime, cutime and cstime are fields 14 to 17.
    let rest = &stat[stat.rfind(')')? + 1..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks = (11..15)
        .map(|i| fields.get(i)?.parse::<f64>().ok())
        .sum::<Option<f64>>()?;
    Some(ticks / CLOCK_TICKS_PER_SECOND)
}

/// Peak resident set size (`VmHWM`), MiB.
pub fn peak_rss_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn figures_are_plausible_on_linux() {
        if !std::path::Path::new("/proc/self/stat").exists() {
            return;
        }
        let before = cpu_seconds().unwrap();
        let mut x = 0u64;
        let start = std::time::Instant::now();
        while start.elapsed().as_millis() < 300 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
        }
        std::hint::black_box(x);
        assert!(cpu_seconds().unwrap() - before >= 0.1);
        assert!(peak_rss_mib().unwrap() > 0.5);
    }

    #[test]
    fn a_waited_child_counts() {
        if !std::path::Path::new("/proc/self/stat").exists() {
            return;
        }
        let before = cpu_seconds().unwrap();
        // A child that spins for about 0.3 s of CPU, then is waited for.
        let status = std::process::Command::new("sh")
            .args(["-c", "i=0; while [ $i -lt 200000 ]; do i=$((i+1)); done"])
            .status();
        let Ok(status) = status else {
            return;
        };
        assert!(status.success());
        assert!(cpu_seconds().unwrap() - before >= 0.05);
    }
}
