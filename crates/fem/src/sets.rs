//! Named sets of mesh entities (node sets, face sets): one registry used by
//! every mesh type ([`crate::Mesh`], [`crate::Mesh3`],
//! [`crate::MembraneMesh`]).

use crate::{FemError, Result};

/// Named lists of `T` (node indices, faces), in insertion order.
#[doc(hidden)]
#[derive(Debug, Clone)]
pub struct NamedSets<T> {
    /// What a set holds, for error messages ("node", "face").
    what: &'static str,
    sets: Vec<(String, Vec<T>)>,
}

impl<T> NamedSets<T> {
    /// No sets; `what` names the entities in error messages.
    pub(crate) fn new(what: &'static str) -> Self {
        Self {
            what,
            sets: Vec::new(),
        }
    }

    /// Adds (or replaces) the set `name`.
    pub(crate) fn insert(&mut self, name: &str, items: Vec<T>) {
        if let Some(s) = self.sets.iter_mut().find(|s| s.0 == name) {
            s.1 = items;
        } else {
            self.sets.push((name.to_owned(), items));
        }
    }

    /// Whether a set `name` exists.
    pub(crate) fn contains(&self, name: &str) -> bool {
        self.sets.iter().any(|s| s.0 == name)
    }

    /// The set `name`.
    ///
    /// # Errors
    /// [`FemError::Mesh`] naming the set if there is none.
    pub(crate) fn get(&self, name: &str) -> Result<&[T]> {
        self.sets
            .iter()
            .find(|s| s.0 == name)
            .map(|s| s.1.as_slice())
            .ok_or_else(|| FemError::Mesh(format!("no {} set named `{name}`", self.what)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn insert_replaces_a_set_of_the_same_name_and_missing_sets_are_named() {
        let mut s = NamedSets::new("node");
        s.insert("top", vec![1, 2]);
        s.insert("top", vec![3]);
        assert_eq!(s.get("top").unwrap(), &[3]);
        assert!(s.contains("top"));
        let e = s.get("base").unwrap_err().to_string();
        assert!(e.contains("no node set named `base`"), "{e}");
    }
}
