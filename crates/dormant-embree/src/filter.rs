//! Geometries that rays skip: [`GeometrySet`], and the argument filter through which a
//! [`super::SceneView`] made by [`super::SceneView::skipping`] rejects every hit inside an
//! instance whose geometry id (in the traced scene) is in the set.
//!
//! The set is handed to Embree inside the ray query context (rtcIntersect1(3): a context may
//! be embedded in a larger struct that the filter reads back); the filter is an argument
//! filter, so it runs only in queries that pass it (a view without a set traces as before),
//! and only on geometries that enable it ([`super::TriangleGeometry::with_argument_filter`]:
//! the prototypes). Invoking it on every geometry (`RTC_RAY_QUERY_FLAG_INVOKE_ARGUMENT_FILTER`)
//! also ran it on the static scene's triangles, which changed which of two triangles sharing
//! an edge a ray exactly on that edge reports.
//!
//! [`OccluderContext`] does invoke its filter on every geometry: an occlusion query through it
//! also learns what blocked the ray (the instance of the hit it stopped at). Which of two hits
//! stops an any-hit query may differ, but whether there is one does not.

use embree4_sys as sys;

/// A set of geometry ids, as a bit set (ids are dense: instance slots).
#[derive(Clone, Debug, Default)]
pub struct GeometrySet {
    words: Vec<u64>,
    len: usize,
}

impl GeometrySet {
    pub fn insert(&mut self, id: u32) {
        let (w, bit) = (id as usize / 64, 1u64 << (id % 64));
        if w >= self.words.len() {
            self.words.resize(w + 1, 0);
        }
        if self.words[w] & bit == 0 {
            self.words[w] |= bit;
            self.len += 1;
        }
    }

    pub fn contains(&self, id: u32) -> bool {
        self.words.get(id as usize / 64).is_some_and(|w| w & (1u64 << (id % 64)) != 0)
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The ids in the set, ascending.
    pub fn iter(&self) -> impl Iterator<Item = u32> + '_ {
        self.words.iter().enumerate().flat_map(|(w, &word)| {
            (0..64u32).filter(move |b| word & (1u64 << b) != 0).map(move |b| w as u32 * 64 + b)
        })
    }

    pub fn clear(&mut self) {
        self.words.clear();
        self.len = 0;
    }
}

/// Embree's ray query context followed by the set its filter reads. `repr(C)` with the
/// context first, so a pointer to the context is a pointer to this.
#[repr(C)]
pub(super) struct SkipContext<'a> {
    base: sys::RTCRayQueryContext,
    skip: &'a GeometrySet,
}

impl<'a> SkipContext<'a> {
    /// rtcInitRayQueryContext, then the set.
    pub(super) fn new(skip: &'a GeometrySet) -> Self {
        let invalid = [sys::RTC_INVALID_GEOMETRY_ID; sys::RTC_MAX_INSTANCE_LEVEL_COUNT as usize];
        Self { base: sys::RTCRayQueryContext { instID: invalid, instPrimID: invalid }, skip }
    }

    /// Points `args` at this context and its filter.
    pub(super) fn intersect_args(&mut self, args: &mut sys::RTCIntersectArguments) {
        args.context = &mut self.base;
        args.filter = Some(skip_filter);
    }

    /// Points `args` at this context and its filter.
    pub(super) fn occluded_args(&mut self, args: &mut sys::RTCOccludedArguments) {
        args.context = &mut self.base;
        args.filter = Some(skip_filter);
    }
}

/// The query context of an occlusion ray that records what blocked it: Embree's context, the
/// skipped set (if any), then the instance and geometry of the first hit the filter accepted
/// (`RTC_INVALID_GEOMETRY_ID` until one is).
#[repr(C)]
pub(super) struct OccluderContext<'a> {
    base: sys::RTCRayQueryContext,
    skip: Option<&'a GeometrySet>,
    pub(super) inst: u32,
    pub(super) geom: u32,
}

impl<'a> OccluderContext<'a> {
    pub(super) fn new(skip: Option<&'a GeometrySet>) -> Self {
        let invalid = [sys::RTC_INVALID_GEOMETRY_ID; sys::RTC_MAX_INSTANCE_LEVEL_COUNT as usize];
        Self {
            base: sys::RTCRayQueryContext { instID: invalid, instPrimID: invalid },
            skip,
            inst: sys::RTC_INVALID_GEOMETRY_ID,
            geom: sys::RTC_INVALID_GEOMETRY_ID,
        }
    }

    /// Points `args` at this context and its filter, invoked on every geometry.
    pub(super) fn occluded_args(&mut self, args: &mut sys::RTCOccludedArguments) {
        args.flags |= sys::RTCRayQueryFlags::RTC_RAY_QUERY_FLAG_INVOKE_ARGUMENT_FILTER;
        args.context = &mut self.base;
        args.filter = Some(record_filter);
    }
}

/// rtcInitIntersectArguments (an inline function in the headers, so not in the bindings).
pub(super) fn intersect_args(flags: sys::RTCRayQueryFlags::Type) -> sys::RTCIntersectArguments {
    sys::RTCIntersectArguments {
        flags,
        feature_mask: sys::RTCFeatureFlags::RTC_FEATURE_FLAG_ALL,
        context: std::ptr::null_mut(),
        filter: None,
        intersect: None,
    }
}

/// rtcInitOccludedArguments.
pub(super) fn occluded_args(flags: sys::RTCRayQueryFlags::Type) -> sys::RTCOccludedArguments {
    sys::RTCOccludedArguments {
        flags,
        feature_mask: sys::RTCFeatureFlags::RTC_FEATURE_FLAG_ALL,
        context: std::ptr::null_mut(),
        filter: None,
        occluded: None,
    }
}

/// Rejects the candidate hits of lanes whose top-level instance id is in the set.
unsafe extern "C" fn skip_filter(args: *const sys::RTCFilterFunctionNArguments) {
    // SAFETY: Embree passes valid arguments for the duration of the call: `valid` points to
    // `N` ints and `hit` to an RTCHitN of width `N`, whose instID[0] lanes start at `7 * N`
    // u32s (RTCHitN_instID in rtcore_ray.h); the filter is only installed by `SkipContext`,
    // so `context` points to the `base` field, the first of a live `SkipContext`.
    unsafe {
        let a = &*args;
        let n = a.N as usize;
        let ctx = &*(a.context as *const SkipContext<'_>);
        let valid = std::slice::from_raw_parts_mut(a.valid, n);
        let inst = std::slice::from_raw_parts((a.hit as *const u32).add(7 * n), n);
        for (v, &id) in valid.iter_mut().zip(inst) {
            if *v != 0 && id != sys::RTC_INVALID_GEOMETRY_ID && ctx.skip.contains(id) {
                *v = 0;
            }
        }
    }
}

/// Rejects the candidate hits of lanes whose top-level instance id is skipped, like
/// [`skip_filter`], and records the first hit it accepts in the [`OccluderContext`].
unsafe extern "C" fn record_filter(args: *const sys::RTCFilterFunctionNArguments) {
    // SAFETY: as in `skip_filter` (geomID lanes start at `6 * N` u32s, RTCHitN_geomID); the
    // filter is only installed by `OccluderContext`, so `context` points to the `base` field,
    // the first of a live `OccluderContext` that the query exclusively borrows.
    unsafe {
        let a = &*args;
        let n = a.N as usize;
        let ctx = &mut *(a.context as *mut OccluderContext<'_>);
        let valid = std::slice::from_raw_parts_mut(a.valid, n);
        let geom = std::slice::from_raw_parts((a.hit as *const u32).add(6 * n), n);
        let inst = std::slice::from_raw_parts((a.hit as *const u32).add(7 * n), n);
        for ((v, &id), &g) in valid.iter_mut().zip(inst).zip(geom) {
            if *v == 0 {
                continue;
            }
            if id != sys::RTC_INVALID_GEOMETRY_ID && ctx.skip.is_some_and(|s| s.contains(id)) {
                *v = 0;
            } else if ctx.geom == sys::RTC_INVALID_GEOMETRY_ID {
                (ctx.inst, ctx.geom) = (id, g);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::GeometrySet;

    #[test]
    fn the_set_counts_and_lists_its_ids() {
        let mut s = GeometrySet::default();
        assert!(s.is_empty());
        for id in [3, 64, 3, 200] {
            s.insert(id);
        }
        assert_eq!(s.iter().collect::<Vec<_>>(), vec![3, 64, 200]);
        assert!(s.contains(3) && s.contains(64) && !s.contains(7) && !s.is_empty());
    }
}
