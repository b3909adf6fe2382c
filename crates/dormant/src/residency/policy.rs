//! When and how to integrate sleeping islands: the policy and the settings a run chooses.

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

/// A run's integration settings, as a user chooses them (`--integration`, `--integrate-as`,
/// `--cache`, `--lookahead`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct IntegrationSettings {
    pub policy: IntegrationPolicy,
    pub form: super::IntegrationForm,
    /// Serve reactivations of baked islands from the geometry cache.
    pub cache: bool,
    /// Let the cost model use the run's known future (each island's true remaining sleep).
    pub lookahead: bool,
}

impl Default for IntegrationSettings {
    fn default() -> Self {
        Self {
            policy: IntegrationPolicy::Auto,
            form: super::IntegrationForm::default(),
            cache: true,
            lookahead: true,
        }
    }
}
