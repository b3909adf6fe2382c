//! Island identity: turns per-step sleep observations into a clean stream of
//! [`IslandEvent`]s with stable ids.
//!
//! An island id names one exact set of sleeping bodies with the poses they fell asleep in.
//! A group of bodies that falls asleep gets a new id (`Slept`). The id ends (`Woke`) as soon
//! as that exact group stops being one sleeping group: any member wakes (a partial wake
//! ends the whole id), is removed from the world, or the group merges with another or
//! splits. Bodies still asleep after such a change form new islands with new ids in the
//! same update. So an id's bodies and poses never change while it lives, which is what a
//! renderer that bakes sleeping islands needs.

use std::collections::btree_map::Entry;
use std::collections::BTreeMap;

use super::body::{BodyId, BodyPose};

/// A sleeping island's identity; never reused within a simulation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize)]
pub struct IslandId(pub u64);

/// A change in the set of sleeping islands.
#[derive(Clone, Debug, PartialEq)]
pub enum IslandEvent {
    /// `bodies` (ascending) fell asleep together, at `poses` (same order).
    Slept { island: IslandId, bodies: Vec<BodyId>, poses: Vec<BodyPose> },
    /// The island ended: some of its bodies moved, were removed, or regrouped.
    Woke { island: IslandId },
}

impl IslandEvent {
    pub fn island(&self) -> IslandId {
        match self {
            IslandEvent::Slept { island, .. } | IslandEvent::Woke { island } => *island,
        }
    }
}

/// One body's state after a step, as the tracker needs it. `group` is `Some(key)` when the
/// body sleeps; sleeping bodies with equal keys in one update form one island. Keys only need
/// to be consistent within one update (Rapier's island ids are not stable across steps).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct SleepObservation {
    pub body: BodyId,
    pub group: Option<u64>,
    pub pose: BodyPose,
}

/// One update's sleeping bodies by group.
struct Sleepers {
    /// Per body id: its group key, if it sleeps.
    group_of: Vec<Option<u64>>,
    /// Per body id: the index of its observation (`u32::MAX`: not observed).
    observation_of: Vec<u32>,
    /// The sleeping bodies of each group key, ascending.
    groups: BTreeMap<u64, Vec<BodyId>>,
}

impl Sleepers {
    fn of(observations: &[SleepObservation]) -> Self {
        let max_body = observations.iter().map(|o| o.body.0 as usize + 1).max().unwrap_or(0);
        let mut group_of = vec![None; max_body];
        let mut observation_of = vec![u32::MAX; max_body];
        let mut groups: BTreeMap<u64, Vec<BodyId>> = BTreeMap::new();
        // Bodies of one group usually come one after another: collect a run of equal keys
        // before looking its group up.
        let mut run: Option<(u64, Vec<BodyId>)> = None;
        for (i, o) in observations.iter().enumerate() {
            let b = o.body.0 as usize;
            debug_assert!(observation_of[b] == u32::MAX, "body {:?} observed twice", o.body);
            observation_of[b] = i as u32;
            let Some(key) = o.group else { continue };
            group_of[b] = Some(key);
            match &mut run {
                Some((k, members)) if *k == key => members.push(o.body),
                _ => {
                    if let Some((k, members)) = run.replace((key, vec![o.body])) {
                        add_run(&mut groups, k, members);
                    }
                }
            }
        }
        if let Some((k, members)) = run {
            add_run(&mut groups, k, members);
        }
        for members in groups.values_mut() {
            members.sort_unstable();
        }
        Sleepers { group_of, observation_of, groups }
    }
}

/// Adds a run of `members` of group `key` to `groups`.
fn add_run(groups: &mut BTreeMap<u64, Vec<BodyId>>, key: u64, members: Vec<BodyId>) {
    match groups.entry(key) {
        Entry::Vacant(e) => {
            e.insert(members);
        }
        Entry::Occupied(mut e) => e.get_mut().extend(members),
    }
}

/// Per-tracker counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct IslandCounters {
    pub updates: u64,
    pub(crate) islands_slept: u64,
    pub islands_woke: u64,
    pub(crate) bodies_slept: u64,
}

/// Keeps the set of sleeping islands and emits events as it changes.
#[derive(Clone, Debug, Default)]
pub(crate) struct IslandTracker {
    next_id: u64,
    islands: BTreeMap<IslandId, Vec<BodyId>>,
    island_of: Vec<Option<IslandId>>,
    counters: IslandCounters,
}

impl IslandTracker {
    pub(crate) fn new() -> Self {
        Self::default()
    }

    /// Feeds the observations of one step (every body in the world, any order; a body not
    /// listed counts as awake or gone) and returns that step's events: all `Woke` events
    /// first, then all `Slept` events, each in ascending id order.
    pub(crate) fn update(&mut self, observations: &[SleepObservation]) -> Vec<IslandEvent> {
        self.counters.updates += 1;
        let Sleepers { group_of, observation_of, groups } = Sleepers::of(observations);
        let max_body = group_of.len();

        let mut events = Vec::new();
        // End every island that is no longer exactly one sleeping group.
        let ended: Vec<IslandId> = self
            .islands
            .iter()
            .filter(|(_, bodies)| {
                let key = group_of.get(bodies[0].0 as usize).copied().flatten();
                let intact = key.is_some_and(|k| {
                    groups[&k].len() == bodies.len()
                        && bodies.iter().all(|b| group_of.get(b.0 as usize).copied().flatten() == Some(k))
                });
                !intact
            })
            .map(|(&id, _)| id)
            .collect();
        for id in ended {
            for b in self.islands.remove(&id).expect("ended island exists") {
                self.island_of[b.0 as usize] = None;
            }
            self.counters.islands_woke += 1;
            events.push(IslandEvent::Woke { island: id });
        }

        // Every sleeping group not already an island is a new one. Order new ids by each
        // group's smallest body so ids do not depend on the grouping keys.
        let mut fresh: Vec<Vec<BodyId>> = groups
            .into_values()
            .filter(|members| self.island_of.get(members[0].0 as usize).copied().flatten().is_none())
            .collect();
        fresh.sort_unstable_by_key(|members| members[0]);
        for bodies in fresh {
            let id = IslandId(self.next_id);
            self.next_id += 1;
            if self.island_of.len() < max_body {
                self.island_of.resize(max_body, None);
            }
            for b in &bodies {
                debug_assert!(self.island_of[b.0 as usize].is_none(), "body {b:?} in two islands");
                self.island_of[b.0 as usize] = Some(id);
            }
            let poses =
                bodies.iter().map(|b| observations[observation_of[b.0 as usize] as usize].pose).collect();
            self.counters.islands_slept += 1;
            self.counters.bodies_slept += bodies.len() as u64;
            self.islands.insert(id, bodies.clone());
            events.push(IslandEvent::Slept { island: id, bodies, poses });
        }
        self.debug_check();
        events
    }

    /// The sleeping island `body` belongs to.
    pub(crate) fn island_of(&self, body: BodyId) -> Option<IslandId> {
        self.island_of.get(body.0 as usize).copied().flatten()
    }

    /// Live sleeping islands, ascending by id, with their bodies (ascending).
    pub(crate) fn islands(&self) -> impl Iterator<Item = (IslandId, &[BodyId])> {
        self.islands.iter().map(|(&id, b)| (id, b.as_slice()))
    }

    pub(crate) fn counters(&self) -> &IslandCounters {
        &self.counters
    }

    fn debug_check(&self) {
        if cfg!(debug_assertions) {
            let members: usize = self.islands.values().map(Vec::len).sum();
            let assigned = self.island_of.iter().filter(|i| i.is_some()).count();
            debug_assert_eq!(members, assigned, "each body in at most one sleeping island");
            for (id, bodies) in &self.islands {
                debug_assert!(!bodies.is_empty());
                debug_assert!(bodies.iter().all(|b| self.island_of[b.0 as usize] == Some(*id)));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obs(body: u32, group: Option<u64>) -> SleepObservation {
        SleepObservation {
            body: BodyId(body),
            group,
            pose: BodyPose { translation: glam::Vec3::splat(body as f32), rotation: glam::Quat::IDENTITY },
        }
    }

    fn slept(events: &[IslandEvent]) -> Vec<Vec<u32>> {
        events
            .iter()
            .filter_map(|e| match e {
                IslandEvent::Slept { bodies, .. } => Some(bodies.iter().map(|b| b.0).collect()),
                _ => None,
            })
            .collect()
    }

    fn woke(events: &[IslandEvent]) -> usize {
        events.iter().filter(|e| matches!(e, IslandEvent::Woke { .. })).count()
    }

    #[test]
    fn a_group_falls_asleep_once_and_keeps_its_id() {
        let mut t = IslandTracker::new();
        let e = t.update(&[obs(0, Some(9)), obs(1, Some(9)), obs(2, None)]);
        assert_eq!(slept(&e), vec![vec![0, 1]]);
        // Rapier may renumber its island: same members, new key, no events.
        let e = t.update(&[obs(0, Some(3)), obs(1, Some(3)), obs(2, None)]);
        assert!(e.is_empty());
        assert_eq!(t.island_of(BodyId(0)), Some(IslandId(0)));
    }

    #[test]
    fn partial_wake_ends_the_island_and_regroups_the_sleepers() {
        let mut t = IslandTracker::new();
        t.update(&[obs(0, Some(1)), obs(1, Some(1)), obs(2, Some(1))]);
        let e = t.update(&[obs(0, None), obs(1, Some(1)), obs(2, Some(1))]);
        assert_eq!(woke(&e), 1);
        assert_eq!(slept(&e), vec![vec![1, 2]]);
        assert_eq!(t.island_of(BodyId(1)), Some(IslandId(1)));
        assert_eq!(t.island_of(BodyId(0)), None);
    }

    #[test]
    fn merge_and_split_make_new_ids() {
        let mut t = IslandTracker::new();
        t.update(&[obs(0, Some(1)), obs(1, Some(2))]);
        assert_eq!(t.islands().count(), 2);
        let e = t.update(&[obs(0, Some(5)), obs(1, Some(5))]);
        assert_eq!(woke(&e), 2);
        assert_eq!(slept(&e), vec![vec![0, 1]]);
        let e = t.update(&[obs(0, Some(5)), obs(1, Some(6))]);
        assert_eq!(woke(&e), 1);
        assert_eq!(slept(&e), vec![vec![0], vec![1]]);
    }

    #[test]
    fn removed_body_ends_its_island() {
        let mut t = IslandTracker::new();
        t.update(&[obs(0, Some(1)), obs(1, Some(1))]);
        let e = t.update(&[obs(1, Some(1))]);
        assert_eq!(woke(&e), 1);
        assert_eq!(slept(&e), vec![vec![1]]);
    }
}
