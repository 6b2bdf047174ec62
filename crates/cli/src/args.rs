//! Argument types shared by subcommands, parsed and validated by clap.

use std::fmt;
use std::str::FromStr;

/// `--shard i/n`: this process does the `i`-th of `n` equal parts of a batch
/// of independent runs (1-based, as Slurm array indices usually are:
/// `--shard $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT`).
///
/// ```
/// use nlvid_cli::args::Shard;
/// let s: Shard = "2/3".parse().unwrap();
/// // 10 runs split 4 + 3 + 3: shard 2 takes runs 4, 5, 6 (0-based).
/// assert_eq!(s.range(10), 4..7);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    index: usize,
    count: usize,
}

impl Shard {
    /// The whole batch in one shard.
    pub const ALL: Self = Self { index: 1, count: 1 };

    /// 1-based shard index.
    pub fn index(&self) -> usize {
        self.index
    }

    /// Number of shards.
    pub fn count(&self) -> usize {
        self.count
    }

    /// The 0-based run indices of this shard among `total` runs: contiguous,
    /// sizes differ by at most one, the earlier shards taking the extra runs;
    /// the shards of `1/n … n/n` partition `0..total` exactly.
    pub fn range(&self, total: usize) -> std::ops::Range<usize> {
        let (q, r) = (total / self.count, total % self.count);
        let k = self.index - 1;
        let start = k * q + k.min(r);
        let len = q + usize::from(k < r);
        start..start + len
    }
}

impl FromStr for Shard {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| format!("`{s}`: expected i/n, e.g. 3/16"))?;
        let i: usize = i
            .trim()
            .parse()
            .map_err(|_| format!("`{s}`: shard index `{i}` is not a positive integer"))?;
        let n: usize = n
            .trim()
            .parse()
            .map_err(|_| format!("`{s}`: shard count `{n}` is not a positive integer"))?;
        if n == 0 || i == 0 || i > n {
            return Err(format!(
                "`{s}`: need 1 <= i <= n (shards are numbered from 1)"
            ));
        }
        Ok(Self { index: i, count: n })
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// Parses a command-line quantity such as `--dt 1ms` or `--speed "5 um/s"`
/// into SI, checking its dimension; for clap's `value_parser`:
/// `#[arg(long, value_parser = |s: &str| quantity(s, Dimension::TIME))]`.
///
/// # Errors
/// A message naming the text, the unit problem or the wrong dimension.
pub fn quantity(text: &str, dim: nlvid_study::Dimension) -> Result<f64, String> {
    let q = nlvid_study::Quantity::parse(text).map_err(|e| format!("`{text}`: {e}"))?;
    if q.dim == dim {
        Ok(q.value)
    } else if q.dim == nlvid_study::Dimension::NONE {
        Err(format!(
            "`{text}` has no unit; expected a {dim}, e.g. \"{text} {}\"",
            dim.example_unit()
        ))
    } else {
        Err(format!("`{text}` is a {}, expected a {dim}", q.dim))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn command_line_quantities_are_checked_and_converted() {
        use nlvid_study::Dimension;
        assert_eq!(quantity("1ms", Dimension::TIME), Ok(1e-3));
        assert_eq!(
            quantity("2", Dimension::TIME).unwrap_err(),
            "`2` has no unit; expected a time (s), e.g. \"2 s\""
        );
        assert_eq!(
            quantity("2 um", Dimension::TIME).unwrap_err(),
            "`2 um` is a length (m), expected a time (s)"
        );
    }

    #[test]
    fn shards_partition_every_batch_exactly() {
        for total in 0..40 {
            for n in 1..9 {
                let mut next = 0;
                for i in 1..=n {
                    let r = Shard { index: i, count: n }.range(total);
                    assert_eq!(r.start, next, "total {total}, shard {i}/{n}");
                    assert!(r.len() == total / n || r.len() == total / n + 1);
                    next = r.end;
                }
                assert_eq!(next, total);
            }
        }
    }

    #[test]
    fn bad_shards_are_rejected_with_a_reason() {
        assert_eq!(
            "3/16".parse::<Shard>().map(|s| s.to_string()),
            Ok("3/16".into())
        );
        assert!(
            "0/4"
                .parse::<Shard>()
                .unwrap_err()
                .contains("numbered from 1")
        );
        assert!("5/4".parse::<Shard>().is_err());
        assert!("4".parse::<Shard>().unwrap_err().contains("expected i/n"));
        assert!(
            "a/4"
                .parse::<Shard>()
                .unwrap_err()
                .contains("shard index `a`")
        );
        assert!("1/0".parse::<Shard>().is_err());
    }
}
