//! [`BuildQuality`]: how much work Embree puts into a BVH, for scenes and for the own BVHs of
//! triangle geometries.

use embree4_sys as sys;

/// Embree's BVH build quality (rtcSetSceneBuildQuality(3), rtcSetGeometryBuildQuality(3)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BuildQuality {
    Low,
    #[default]
    Medium,
    High,
}

impl BuildQuality {
    pub const ALL: [BuildQuality; 3] = [BuildQuality::Low, BuildQuality::Medium, BuildQuality::High];

    pub(crate) fn raw(self) -> sys::RTCBuildQuality::Type {
        use sys::RTCBuildQuality::*;
        match self {
            BuildQuality::Low => RTC_BUILD_QUALITY_LOW,
            BuildQuality::Medium => RTC_BUILD_QUALITY_MEDIUM,
            BuildQuality::High => RTC_BUILD_QUALITY_HIGH,
        }
    }
}
