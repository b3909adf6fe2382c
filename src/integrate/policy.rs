//! When to integrate a sleeping island.

/// The integration policy (`--integration`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum IntegrationPolicy {
    /// Never integrate: every body stays an instance (the instanced baseline).
    Never,
    /// Integrate every island as soon as it sleeps.
    Always,
    /// Integrate when the cost model expects the build to pay off before the island wakes.
    Auto,
}

impl std::fmt::Display for IntegrationPolicy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            IntegrationPolicy::Never => "never",
            IntegrationPolicy::Always => "always",
            IntegrationPolicy::Auto => "auto",
        })
    }
}
