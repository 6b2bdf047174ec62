//! The text of a study file and the mapping from byte offsets to lines.

use std::path::PathBuf;

use crate::error::Location;

/// A loaded study text with its name and the directory relative paths resolve against.
#[derive(Debug)]
pub(crate) struct Source {
    pub name: String,
    pub text: String,
    pub base_dir: PathBuf,
    line_starts: Vec<usize>,
}

impl Source {
    pub fn new(name: String, text: String, base_dir: PathBuf) -> Self {
        let mut line_starts = vec![0];
        line_starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        Self {
            name,
            text,
            base_dir,
            line_starts,
        }
    }

    /// 1-based line and character column of a byte offset.
    pub fn locate(&self, offset: usize) -> Location {
        let offset = offset.min(self.text.len());
        let line = self.line_starts.partition_point(|&s| s <= offset);
        let start = self.line_starts[line.saturating_sub(1)];
        let column = self
            .text
            .get(start..offset)
            .map_or(offset - start, |s| s.chars().count())
            + 1;
        Location {
            file: self.name.clone(),
            line,
            column,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_map_to_one_based_lines_and_columns() {
        let s = Source::new("f.toml".into(), "ab\nµx = 1\n".into(), PathBuf::new());
        assert_eq!((s.locate(0).line, s.locate(0).column), (1, 1));
        assert_eq!((s.locate(3).line, s.locate(3).column), (2, 1));
        // 'x' follows the two-byte 'µ': byte 5, character column 2.
        assert_eq!((s.locate(5).line, s.locate(5).column), (2, 2));
    }
}
