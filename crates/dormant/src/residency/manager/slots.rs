//! The scene manager's bookkeeping: where each body is, which islands sleep, and who owns
//! each static mesh and instance (every hit looks here).

use std::collections::BTreeMap;
use std::sync::Arc;

use glam::{Affine3A, Mat3};

use crate::accel::{normal_matrix, InstanceId, StaticId, StaticSceneSnapshot};
use crate::physics::{BodyId, BodyPose, IslandId};
use crate::residency::baked::BakedIsland;

/// A body's place in the accelerator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Placement {
    Absent,
    /// In the per-frame top level.
    Instance {
        id: InstanceId,
        pose: BodyPose,
    },
    /// Baked into the static scene with its island.
    Baked(IslandId),
    /// An instance in the resting scene with its island.
    Resting {
        island: IslandId,
        id: InstanceId,
        pose: BodyPose,
    },
}

pub(super) struct BodySlot {
    pub prototype: u32,
    pub placement: Placement,
}

pub(super) struct SleepingIsland {
    pub bodies: Vec<BodyId>,
    pub poses: Vec<BodyPose>,
    /// Rendered-frame counter when it fell asleep.
    pub(crate) slept_at: u32,
    /// Whether a decision about it was logged.
    pub(crate) decided: bool,
}

/// A baked island in the static scene.
#[derive(Clone)]
pub(super) struct Integrated {
    pub id: StaticId,
    pub baked: Arc<BakedIsland>,
}

/// What a static mesh belongs to.
#[derive(Clone)]
pub(super) enum StaticOwner {
    Environment(u32),
    Island(Arc<BakedIsland>),
}

/// Owners by static id: a dense table, because every hit on static geometry looks here.
#[derive(Default)]
pub(super) struct StaticOwners(Vec<Option<StaticOwner>>);

impl StaticOwners {
    pub(crate) fn insert(&mut self, id: StaticId, owner: StaticOwner) {
        let i = id.0 as usize;
        if self.0.len() <= i {
            self.0.resize(i + 1, None);
        }
        self.0[i] = Some(owner);
    }

    pub(crate) fn remove(&mut self, id: StaticId) {
        if let Some(slot) = self.0.get_mut(id.0 as usize) {
            *slot = None;
        }
    }

    pub(crate) fn get(&self, id: StaticId) -> Option<&StaticOwner> {
        self.0.get(id.0 as usize)?.as_ref()
    }

    pub(crate) fn retain_environment(&mut self) {
        for slot in &mut self.0 {
            if matches!(slot, Some(StaticOwner::Island(_))) {
                *slot = None;
            }
        }
    }
}

/// Who an instance is: its body, prototype, normal matrix, and whether it rests (integrated
/// into the resting scene).
#[derive(Clone, Copy)]
pub(super) struct InstanceOwner {
    pub body: BodyId,
    pub prototype: u32,
    pub(crate) normal_matrix: Mat3,
    /// The object-to-world transform the accelerator was given.
    pub transform: Affine3A,
    pub resting: bool,
}

impl InstanceOwner {
    /// Body `body`, an instance of `prototype` placed by `transform`.
    pub(crate) fn at(body: BodyId, prototype: u32, transform: Affine3A, resting: bool) -> Self {
        Self { body, prototype, normal_matrix: normal_matrix(&transform), transform, resting }
    }
}

/// Owners by instance id (dense, like [`StaticOwners`]), with how many are awake: every frame
/// reports that count, and counting it afresh read every owner (megabytes on the demolition).
#[derive(Default)]
pub(super) struct InstanceOwners {
    owners: Vec<Option<InstanceOwner>>,
    awake: usize,
}

impl InstanceOwners {
    pub(crate) fn set(&mut self, id: InstanceId, owner: Option<InstanceOwner>) {
        let i = id.0 as usize;
        if self.owners.len() <= i {
            self.owners.resize(i + 1, None);
        }
        let awake = |o: &Option<InstanceOwner>| usize::from(o.is_some_and(|o| !o.resting));
        self.awake = self.awake + awake(&owner) - awake(&self.owners[i]);
        self.owners[i] = owner;
    }

    pub(crate) fn get(&self, id: InstanceId) -> Option<&InstanceOwner> {
        self.owners.get(id.0 as usize)?.as_ref()
    }

    /// Marks instance `id` (if it has an owner) as resting or awake.
    pub(crate) fn set_resting(&mut self, id: InstanceId, resting: bool) {
        if let Some(owner) = self.owners.get(id.0 as usize).copied().flatten() {
            self.set(id, Some(InstanceOwner { resting, ..owner }));
        }
    }

    /// Instances in the per-frame top level.
    pub(crate) fn awake(&self) -> usize {
        debug_assert_eq!(self.awake, self.owners.iter().flatten().filter(|o| !o.resting).count());
        self.awake
    }
}

/// A cache entry: a saved static scene and the static ids its islands had in it.
#[derive(Clone)]
pub(super) struct CachedScene {
    pub snapshot: Option<StaticSceneSnapshot>,
    pub ids: BTreeMap<IslandId, StaticId>,
}
