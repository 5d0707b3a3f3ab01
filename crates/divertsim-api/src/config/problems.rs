//! Problems with the input, each tied to its key, and how they are listed.

// The sibling files this one uses, named so that the import-cycle check sees them.
#[allow(unused_imports)]
use super::*;

/// One problem with the input, tied to a key.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Problem {
    /// Dotted key path (`machine.belt_speed`), or the file / option concerned.
    pub key: String,
    pub message: String,
}

impl Problem {
    /// A problem with the value at `key`.
    pub fn new(key: impl Into<String>, message: impl Into<String>) -> Problem {
        Problem {
            key: key.into(),
            message: message.into(),
        }
    }
}

/// Every problem found in the input.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Problems(pub Vec<Problem>);

impl fmt::Display for Problems {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = self.0.len();
        writeln!(
            f,
            "invalid input: {n} problem{}",
            if n == 1 { "" } else { "s" }
        )?;
        for p in self.0.iter().take(MAX_LISTED) {
            writeln!(f, "  - {}: {}", p.key, p.message)?;
        }
        if n > MAX_LISTED {
            writeln!(f, "  ... and {} more problems", n - MAX_LISTED)?;
        }
        Ok(())
    }
}

impl std::error::Error for Problems {}

/// Problems listed one by one before "and N more".
pub const MAX_LISTED: usize = 64;
