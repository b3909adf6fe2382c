//! The integration forms: how a sleeping island is held once it is integrated ([`IntegrationForm`],
//! `--integrate-as`).

use crate::names::named_enum;

named_enum! {
    /// How integrated islands are held (`--integrate-as`).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
    #[serde(rename_all = "lowercase")]
    pub enum IntegrationForm {
        /// The island's triangles in world space, in the static scene (one incremental insert).
        Baked = "baked",
        /// The island's bodies stay instances, in a resting scene beside the per-frame top level:
        /// rebuilt on a schedule, traced as a second scene per ray.
        ///
        /// The default: on the monastery with 8,000 ducks it traces 0.98x (Embree) and 0.87-1.0x (BVH) as fast as every body
        /// instanced in one top level, where baking every body traces 1.7-1.8x slower (`dormant
        /// bench accel`): docs/lab/accelerators.md#2026-12-01-integration-forms-on-the-same-scene-and-the-ratios-table
        #[default]
        Resting = "resting",
    }
}

impl IntegrationForm {
    /// Every form, the default first.
    pub const ALL: [IntegrationForm; 2] = [IntegrationForm::Resting, IntegrationForm::Baked];

    /// Every form with `first` first.
    pub fn starting_with(first: IntegrationForm) -> Vec<IntegrationForm> {
        let mut forms = vec![first];
        forms.extend(Self::ALL.into_iter().filter(|f| *f != first));
        forms
    }
}
