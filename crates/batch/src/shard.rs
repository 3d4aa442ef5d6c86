//! Which clips a worker takes: its shard of the manifest.
//!
//! A clip belongs to shard `FNV-1a-64(id) mod N` (the 64-bit FNV-1a hash of the clip id's UTF-8
//! bytes): the rule depends on nothing but the clip's own name, so a clip keeps its shard when
//! the manifest grows or is reordered, and any script can compute it.
//!
//! The shard index and count come from the flags, else from the scheduler's variables:
//! Slurm array jobs (`SLURM_ARRAY_TASK_ID` − `SLURM_ARRAY_TASK_MIN`, `SLURM_ARRAY_TASK_COUNT`),
//! Kubernetes Indexed Jobs (`JOB_COMPLETION_INDEX`, the count from `--shard-count` or
//! `VISAGE_SHARD_COUNT`), AWS Batch array jobs (`AWS_BATCH_JOB_ARRAY_INDEX`,
//! `AWS_BATCH_JOB_ARRAY_SIZE`), or `VISAGE_SHARD_INDEX` / `VISAGE_SHARD_COUNT`; without any,
//! one shard holds every clip.

use crate::error::Error;

/// A worker's shard: `index` of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// From 0, below `count`.
    pub index: usize,
    /// At least 1.
    pub count: usize,
    /// Where the index came from (a flag or the scheduler's variable), for the log.
    pub source: &'static str,
}

impl Shard {
    /// Whether the clip named `id` is this shard's.
    pub fn owns(&self, id: &str) -> bool {
        shard_of(id, self.count) == self.index
    }

    /// The shard from the flags (`--shard-index`, `--shard-count`), else from the
    /// scheduler's variables (`var` reads one; see the module docs).
    pub fn resolve(
        index: Option<usize>,
        count: Option<usize>,
        var: impl Fn(&str) -> Option<String>,
    ) -> Result<Shard, Error> {
        let num = |name: &str| -> Result<Option<usize>, Error> {
            var(name)
                .map(|v| {
                    v.trim()
                        .parse::<usize>()
                        .map_err(|source| Error::NotANumber {
                            name: name.to_owned(),
                            value: v.clone(),
                            source,
                        })
                })
                .transpose()
        };
        let count_from_env = || -> Result<Option<usize>, Error> {
            Ok(match count {
                Some(n) => Some(n),
                None => num("VISAGE_SHARD_COUNT")?,
            })
        };
        let (index, count, source) = if let Some(i) = index {
            let n = count.ok_or(Error::IndexWithoutCount)?;
            (i, n, "--shard-index")
        } else if let Some(id) = num("SLURM_ARRAY_TASK_ID")? {
            let min = num("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            let n = match count {
                Some(n) => n,
                None => num("SLURM_ARRAY_TASK_COUNT")?.ok_or(Error::SlurmCountMissing)?,
            };
            if id < min {
                return Err(Error::SlurmIdBelowMin { id, min });
            }
            (id - min, n, "$SLURM_ARRAY_TASK_ID")
        } else if let Some(i) = num("JOB_COMPLETION_INDEX")? {
            let n = count_from_env()?.ok_or(Error::KubernetesCountMissing)?;
            (i, n, "$JOB_COMPLETION_INDEX")
        } else if let Some(i) = num("AWS_BATCH_JOB_ARRAY_INDEX")? {
            let n = match count {
                Some(n) => n,
                None => num("AWS_BATCH_JOB_ARRAY_SIZE")?.ok_or(Error::AwsCountMissing)?,
            };
            (i, n, "$AWS_BATCH_JOB_ARRAY_INDEX")
        } else if let Some(i) = num("VISAGE_SHARD_INDEX")? {
            let n = count_from_env()?.ok_or(Error::VisageCountMissing)?;
            (i, n, "$VISAGE_SHARD_INDEX")
        } else {
            (0, count.unwrap_or(1), "default")
        };
        if count == 0 {
            return Err(Error::ZeroShards { from: source });
        }
        if index >= count {
            return Err(Error::IndexNotBelowCount {
                index,
                from: source,
                count,
            });
        }
        Ok(Shard {
            index,
            count,
            source,
        })
    }
}

/// The shard of the clip named `id` among `count`.
pub fn shard_of(id: &str, count: usize) -> usize {
    (fnv1a64(id.as_bytes()) % count as u64) as usize
}

/// The 64-bit FNV-1a hash.
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(pairs: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |name| {
            pairs
                .iter()
                .find(|(k, _)| *k == name)
                .map(|(_, v)| v.to_string())
        }
    }

    #[test]
    fn fnv1a_matches_the_published_test_vectors() {
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a64(b"foobar"), 0x8594_4171_f739_67e8);
    }

    #[test]
    fn shards_split_every_clip_once_and_keep_it_as_the_manifest_grows() {
        let ids: Vec<String> = (0..1000)
            .map(|i| format!("day{}/clip{i:04}", i % 7))
            .collect();
        let mut sizes = [0usize; 4];
        for id in &ids {
            let owners: Vec<usize> = (0..4)
                .filter(|&i| {
                    Shard {
                        index: i,
                        count: 4,
                        source: "",
                    }
                    .owns(id)
                })
                .collect();
            assert_eq!(owners.len(), 1);
            sizes[owners[0]] += 1;
            // The assignment is a function of the id alone.
            assert_eq!(shard_of(id, 4), owners[0]);
        }
        // Roughly even: each shard within 20 % of a quarter.
        assert!(sizes.iter().all(|&n| (200..300).contains(&n)), "{sizes:?}");
    }

    #[test]
    fn the_schedulers_variables() {
        let s = Shard::resolve(None, None, env(&[])).unwrap();
        assert_eq!((s.index, s.count), (0, 1));
        let s = Shard::resolve(Some(2), Some(5), env(&[("SLURM_ARRAY_TASK_ID", "0")])).unwrap();
        assert_eq!((s.index, s.count), (2, 5));
        let slurm = [
            ("SLURM_ARRAY_TASK_ID", "3"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ];
        let s = Shard::resolve(None, None, env(&slurm)).unwrap();
        assert_eq!((s.index, s.count), (2, 4));
        let k8s = [("JOB_COMPLETION_INDEX", "1"), ("VISAGE_SHARD_COUNT", "3")];
        let s = Shard::resolve(None, None, env(&k8s)).unwrap();
        assert_eq!((s.index, s.count), (1, 3));
        let s = Shard::resolve(None, Some(8), env(&k8s[..1])).unwrap();
        assert_eq!((s.index, s.count), (1, 8));
        let aws = [
            ("AWS_BATCH_JOB_ARRAY_INDEX", "0"),
            ("AWS_BATCH_JOB_ARRAY_SIZE", "2"),
        ];
        assert_eq!(Shard::resolve(None, None, env(&aws)).unwrap().count, 2);
    }

    #[test]
    fn bad_shards_say_why() {
        let err = |i, n, e: &[(&str, &str)]| {
            visage::error_chain(&Shard::resolve(i, n, env(e)).unwrap_err())
        };
        assert!(err(Some(1), None, &[]).contains("--shard-count"));
        assert!(err(Some(4), Some(4), &[]).contains("not below the shard count 4"));
        assert!(err(None, None, &[("JOB_COMPLETION_INDEX", "0")]).contains("VISAGE_SHARD_COUNT"));
        assert!(err(None, None, &[("SLURM_ARRAY_TASK_ID", "x")]).contains("not a whole number"));
        assert!(err(None, Some(0), &[]).contains("at least 1"));
    }
}
