//! [`Backend`]: the accelerator implementations a build can have.

use std::fmt;
use std::str::FromStr;

/// The accelerator implementations dormant can be built with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    /// Intel Embree 4 (feature `embree`).
    Embree,
    /// The pure-Rust BVH (`accel::bvh`), always compiled.
    Bvh,
}

impl Backend {
    pub const ALL: &'static [Backend] = &[Backend::Embree, Backend::Bvh];

    pub fn name(self) -> &'static str {
        match self {
            Backend::Embree => "embree",
            Backend::Bvh => "bvh",
        }
    }

    pub fn is_compiled(self) -> bool {
        match self {
            Backend::Embree => cfg!(feature = "embree"),
            Backend::Bvh => true,
        }
    }

    /// The backends this build can use, preferred first.
    pub fn compiled() -> Vec<Backend> {
        Self::ALL.iter().copied().filter(|b| b.is_compiled()).collect()
    }
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Backend {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .iter()
            .copied()
            .find(|b| b.name() == s)
            .ok_or_else(|| format!("unknown backend '{s}' (expected one of: embree, bvh)"))
    }
}
