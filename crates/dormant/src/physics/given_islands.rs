//! The islands a file records (`dormant export --gltf` writes its simulation's islands and
//! kinematic bodies into the file's `dormant` extras), checked and turned into what
//! `animated` otherwise finds from the motion: each body's rests and the groups that rest
//! together. With them a dormant simulation read back from its glTF replays the same rests as
//! its trajectory, so the residency engine makes the same decisions.

use std::collections::BTreeSet;

use super::body::BodyId;
use crate::scene::gltf::animated::SimulationExtras;

/// Checked islands: per body its rests (first frame, end frame), the groups in the order
/// their ids go, and which bodies are kinematic.
pub(super) struct GivenIslands {
    pub(super) rests: Vec<Vec<(u32, u32)>>,
    pub(super) groups: Vec<((u32, u32), Vec<BodyId>)>,
    pub(super) kinematic: Vec<bool>,
}

/// Checks `given` against `bodies` bodies and `frames` frames: every island starts within
/// the run and ends after it starts, names existing bodies once each, and no body is in two
/// islands at once. The error is the cause.
pub(super) fn given_islands(
    given: &SimulationExtras,
    bodies: usize,
    frames: u32,
) -> Result<GivenIslands, String> {
    let mut rests = vec![Vec::new(); bodies];
    let mut groups = Vec::with_capacity(given.islands.len());
    for (i, (start, end, members)) in given.islands.iter().enumerate() {
        let end = end.unwrap_or(frames);
        if *start >= frames || end <= *start || end > frames {
            return Err(format!("islands[{i}]: frames {start}..{end} are not within the run's {frames}"));
        }
        let unique: BTreeSet<u32> = members.iter().copied().collect();
        if members.is_empty()
            || unique.len() != members.len()
            || unique.last().is_some_and(|&b| b as usize >= bodies)
        {
            return Err(format!("islands[{i}]: bodies must be distinct ids below {bodies}, at least one"));
        }
        for &b in &unique {
            rests[b as usize].push((*start, end));
        }
        groups.push(((*start, end), unique.into_iter().map(BodyId).collect()));
    }
    for (b, r) in rests.iter_mut().enumerate() {
        r.sort_unstable();
        if r.windows(2).any(|w| w[1].0 < w[0].1) {
            return Err(format!("body {b} is in two islands at once"));
        }
    }
    groups.sort_by_key(|g: &((u32, u32), Vec<BodyId>)| g.0 .0);
    let mut kinematic = vec![false; bodies];
    for &b in &given.kinematic {
        let slot =
            kinematic.get_mut(b as usize).ok_or_else(|| format!("kinematic body {b} does not exist"))?;
        *slot = true;
    }
    Ok(GivenIslands { rests, groups, kinematic })
}
