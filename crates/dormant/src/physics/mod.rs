//! Physics: Rapier worlds built from scene files, stepping with spawners, structures built
//! asleep, projectiles, kinematic paths and scripted disturbances, the island tracker that turns Rapier's sleep state into
//! `Slept`/`Woke` events with stable ids, trajectories (recording and replay), island
//! statistics. Rapier's types stay inside this module; everything
//! public speaks glam.

mod animated;
mod body;
mod colliders;
mod error;
mod given_islands;
mod island;
mod island_stats;
mod kinematic;
mod observed;
mod options;
mod simulation;
mod spawn;
mod structures;
pub mod trajectory;

pub use body::{BodyId, BodyInfo, BodyKind, BodyPose, BodyState};
pub use colliders::ColliderChoice;
pub use error::PhysicsError;
pub use island::{IslandEvent, IslandId};
pub use island_stats::IslandStats;
pub use observed::SimulatedFrame;
pub use options::SimulateOptions;
pub use simulation::{simulate, simulate_observed, Simulation};
