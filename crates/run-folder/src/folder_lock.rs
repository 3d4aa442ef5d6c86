//! One writer per output folder at a time: an exclusive lock on the folder's lock file
//! ([`LOCK`]), held for as long as a run, a resume, an `--overwrite` or an export writes there.
//!
//! The lock is the operating system's advisory file lock (`flock` on Unix, `LockFileEx` on
//! Windows, through `std::fs::File::try_lock`), so it is released when its holder exits in any
//! way, a crash or `kill -9` included: there is no stale lock to clean up. The file itself stays
//! in the folder (removing a locked file lets a third writer lock a new file of the same name
//! while the second still holds the old one); while held it tells who holds the lock — process
//! id, host, command and start — for the message that refuses a second writer; let go, it is
//! empty. Either way it marks the folder as one that visage has written to.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use crate::file_names::LOCK;
use crate::RunFolderError as Error;

/// Who holds a folder's lock, as its lock file says.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LockHolder {
    /// The holder's process id.
    pub pid: u32,
    /// The host it runs on.
    pub host: String,
    /// Its command line.
    pub command: String,
    /// When it took the lock, seconds since the Unix epoch.
    pub started_unix_s: f64,
}

impl LockHolder {
    fn this_process() -> LockHolder {
        LockHolder {
            pid: std::process::id(),
            host: host_name(),
            command: std::env::args().collect::<Vec<_>>().join(" "),
            started_unix_s: unix_now_s(),
        }
    }

    /// "pid 1234 on HOST, `COMMAND`, started 12 s ago".
    pub fn describe(&self) -> String {
        let ago = (unix_now_s() - self.started_unix_s).max(0.0);
        format!(
            "pid {} on {}, `{}`, started {} ago",
            self.pid,
            self.host,
            self.command,
            duration(ago)
        )
    }
}

/// A held lock on an output folder; released when dropped (or when the process ends).
#[derive(Debug)]
pub struct FolderLock {
    // Holding the open file holds the lock.
    file: std::fs::File,
    path: PathBuf,
}

impl FolderLock {
    /// Locks `dir` (created if missing) for this process, or says who holds it.
    ///
    /// # Errors
    /// [`Error::Locked`] naming the holder when another process holds the lock; a folder or
    /// lock file that cannot be created or written.
    pub fn acquire(dir: &Path) -> Result<FolderLock, Error> {
        let write_error = |path: &Path| {
            let path = path.to_owned();
            move |source| Error::Write { path, source }
        };
        std::fs::create_dir_all(dir).map_err(write_error(dir))?;
        let path = dir.join(LOCK);
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(write_error(&path))?;
        match file.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                let holder = std::fs::read_to_string(&path)
                    .ok()
                    .and_then(|text| serde_json::from_str::<LockHolder>(&text).ok());
                return Err(Error::Locked {
                    dir: dir.to_owned(),
                    holder: holder.map_or_else(
                        || "another process (it has not said which yet)".to_owned(),
                        |h| h.describe(),
                    ),
                });
            }
            Err(std::fs::TryLockError::Error(source)) => {
                return Err(Error::Write { path, source });
            }
        }
        let text = serde_json::to_string_pretty(&LockHolder::this_process())
            .expect("a lock holder serialises");
        file.set_len(0).map_err(write_error(&path))?;
        file.write_all(text.as_bytes())
            .and_then(|()| file.write_all(b"\n"))
            .and_then(|()| file.sync_data())
            .map_err(write_error(&path))?;
        Ok(FolderLock { file, path })
    }

    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Lets go and removes the lock file: for a folder that was not visage's and that a run
    /// was refused (it must not be marked as a run's).
    pub fn discard(self) {
        // Best effort: a lock file left behind only marks the folder.
        let _ = std::fs::remove_file(&self.path);
    }
}

impl Drop for FolderLock {
    /// Empties the lock file before letting go: a folder at rest holds an empty lock file (the
    /// same in every finished run), and only a holder's name is ever in it.
    fn drop(&mut self) {
        // Best effort: a name left behind is only shown if the lock is held again.
        let _ = self.file.set_len(0);
    }
}

fn unix_now_s() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

/// The machine's name (`/proc/sys/kernel/hostname`, `/etc/hostname`, `$HOSTNAME`,
/// `$COMPUTERNAME`), or "this host".
fn host_name() -> String {
    ["/proc/sys/kernel/hostname", "/etc/hostname"]
        .iter()
        .find_map(|p| std::fs::read_to_string(p).ok())
        .or_else(|| std::env::var("HOSTNAME").ok())
        .or_else(|| std::env::var("COMPUTERNAME").ok())
        .map(|h| h.trim().to_owned())
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "this host".to_owned())
}

/// "4 s", "3 min 20 s", "2 h 5 min".
fn duration(s: f64) -> String {
    let s = s.round() as u64;
    match s {
        0..60 => format!("{s} s"),
        60..3600 => format!("{} min {} s", s / 60, s % 60),
        _ => format!("{} h {} min", s / 3600, s % 3600 / 60),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_writer_is_refused_with_the_first_ones_name_until_it_lets_go() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("run");
        let first = FolderLock::acquire(&out).unwrap();
        let err = FolderLock::acquire(&out).unwrap_err().to_string();
        assert!(err.contains("in use"), "{err}");
        assert!(
            err.contains(&format!("pid {}", std::process::id())),
            "{err}"
        );
        drop(first);
        let again = FolderLock::acquire(&out).unwrap();
        assert_eq!(again.path(), out.join(LOCK));
        // The file names its holder while held, and stays, empty, once let go.
        let holder: LockHolder =
            serde_json::from_str(&std::fs::read_to_string(again.path()).unwrap()).unwrap();
        assert_eq!(holder.pid, std::process::id());
        let path = again.path().to_owned();
        drop(again);
        assert_eq!(std::fs::read(path).unwrap(), b"");
    }

    #[test]
    fn durations_read_as_people_say_them() {
        assert_eq!(duration(4.2), "4 s");
        assert_eq!(duration(200.0), "3 min 20 s");
        assert_eq!(duration(7500.0), "2 h 5 min");
    }
}
