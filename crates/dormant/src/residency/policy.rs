//! When and how to integrate sleeping islands: the policy and the settings a run chooses.

use crate::names::named_enum;

named_enum! {
    /// The integration policy (`--integration`).
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
    #[serde(rename_all = "lowercase")]
    pub enum IntegrationPolicy {
        /// Never integrate: every body stays an instance (the instanced baseline).
        Never = "never",
        /// Integrate every island as soon as it sleeps.
        Always = "always",
        /// Integrate when the cost model expects the build to pay off before the island wakes.
        Auto = "auto",
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
