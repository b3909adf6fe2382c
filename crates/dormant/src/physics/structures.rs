//! Structures at rest: the copies of `[[structures]]` tables, whose bodies enter the world
//! asleep before the first frame and sleep as one island per copy until something wakes them.
//!
//! Rapier gives every body inserted asleep a persistent island of its own, and computes no
//! contacts between sleeping bodies, except for new colliders: a new pair found touching is
//! a contact that starts, and a start wakes both bodies. So a structure's colliders carry a
//! contact filter ([`RestingContacts`]) that drops pairs in which neither body moves, and the
//! blocks of a structure never wake each other (or get woken by the ground) by being placed
//! touching. Since no contact links them, Rapier would wake one block at a time; a structure
//! is meant to be one island, as if it had fallen asleep by itself, so [`StructureSet`] wakes
//! all of a copy's bodies as soon as any of them is awake, and drops the filter from them.
//! Until then the island tracker groups the copy's sleeping bodies under one key, and their
//! poses are the ones they were built in ([`StructureSet::resting`]); once awake they are
//! ordinary bodies whose islands Rapier forms from their contacts.

use rapier3d::prelude::{
    ActiveHooks, PairFilterContext, PhysicsHooks, PhysicsWorld, RigidBodyHandle, SolverFlags,
};

use super::body::{BodyId, BodyPose};
use super::spawn::SpawnOrder;

/// Sleep-group keys of intact structures start here: above Rapier's island ids (`u32`) and
/// the simulation's keys for bodies Rapier does not know (`u32::MAX + 1 + body`).
const STRUCTURE_KEY_BASE: u64 = 1 << 40;

/// Which body belongs to which structure copy, where it was built, and which copies have
/// never woken.
#[derive(Clone, Debug, Default)]
pub(crate) struct StructureSet {
    /// Per body id: the copy it belongs to and the pose it was built in.
    member: Vec<Option<(u32, BodyPose)>>,
    /// Per copy: its bodies while it is intact (asleep since it was built); empty once woken.
    intact: Vec<Vec<BodyId>>,
}

impl StructureSet {
    /// The structures among `orders`, whose bodies get ids from `first_id` on in order.
    pub(crate) fn new(orders: &[SpawnOrder], first_id: u32, body_count: usize) -> Self {
        let mut set = StructureSet { member: vec![None; body_count], intact: Vec::new() };
        for (i, order) in orders.iter().enumerate() {
            let Some(copy) = order.structure else { continue };
            let id = BodyId(first_id + i as u32);
            if set.intact.len() <= copy as usize {
                set.intact.resize(copy as usize + 1, Vec::new());
            }
            set.intact[copy as usize].push(id);
            set.member[id.0 as usize] = Some((copy, order.pose));
        }
        set
    }

    /// Copies that have not woken since they were built.
    pub(crate) fn intact_count(&self) -> usize {
        self.intact.iter().filter(|bodies| !bodies.is_empty()).count()
    }

    /// For a body of an intact copy (asleep where it was built, which Rapier leaves as it is):
    /// the island tracker's group key for its copy, and the pose it was built in.
    pub(crate) fn resting(&self, body: BodyId) -> Option<(u64, BodyPose)> {
        let (copy, pose) = self.member.get(body.0 as usize).copied().flatten()?;
        (!self.intact[copy as usize].is_empty()).then_some((STRUCTURE_KEY_BASE + copy as u64, pose))
    }

    /// Wakes every intact copy with an awake body (all of its bodies, strongly, as Rapier
    /// wakes an island) and drops their contact filter; `handles` maps body ids to Rapier.
    pub(crate) fn wake_touched(&mut self, world: &mut PhysicsWorld, handles: &[Option<RigidBodyHandle>]) {
        if self.intact.is_empty() {
            return;
        }
        let mut touched: Vec<u32> = world
            .islands
            .active_bodies()
            .filter_map(|h| self.member.get(world.bodies[h].user_data as usize).copied().flatten())
            .map(|(copy, _)| copy)
            .filter(|&copy| !self.intact[copy as usize].is_empty())
            .collect();
        touched.sort_unstable();
        touched.dedup();
        for copy in touched {
            for body in std::mem::take(&mut self.intact[copy as usize]) {
                let Some(handle) = handles[body.0 as usize] else { continue };
                world.wake_up(handle, true);
                for &collider in world.bodies[handle].colliders() {
                    if let Some(c) = world.colliders.get_mut(collider) {
                        c.set_active_hooks(ActiveHooks::empty());
                    }
                }
            }
        }
    }
}

/// The contact filter of resting structures: a pair is computed only when one of its bodies
/// moves (dynamic or kinematic, and awake), so blocks built touching stay asleep. Every pair
/// the filter lets through is solved as without it.
pub(crate) struct RestingContacts;

impl PhysicsHooks for RestingContacts {
    fn filter_contact_pair(&self, context: &PairFilterContext) -> Option<SolverFlags> {
        let moves = |h: Option<RigidBodyHandle>| {
            h.and_then(|h| context.bodies.get(h)).is_some_and(|rb| !rb.is_fixed() && !rb.is_sleeping())
        };
        (moves(context.rigid_body1) || moves(context.rigid_body2)).then(SolverFlags::default)
    }
}
