//! [`load_scene`]: a scene description into an accelerator, with ids in a fixed order.

use super::{AccelError, Accelerator, InstanceId, PrototypeId, StaticId};
use crate::scene::SceneDescription;

/// The ids an accelerator gave the parts of a [`SceneDescription`], index for index.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadedScene {
    pub statics: Vec<StaticId>,
    pub prototypes: Vec<PrototypeId>,
    pub instances: Vec<InstanceId>,
}

/// Puts every static mesh, prototype and body of `desc` into `accel` (statics first, then one
/// prototype per mesh, then one instance per body) without committing. Backends assign ids in
/// call order, so two backends loaded from one description agree on every id.
pub fn load_scene(desc: &SceneDescription, accel: &mut dyn Accelerator) -> Result<LoadedScene, AccelError> {
    let mut loaded = LoadedScene::default();
    for s in &desc.statics {
        loaded.statics.push(accel.add_static(&s.mesh)?);
    }
    for p in &desc.prototypes {
        loaded.prototypes.push(accel.add_prototype(&p.mesh)?);
    }
    for b in &desc.bodies {
        let proto = *loaded
            .prototypes
            .get(b.prototype as usize)
            .ok_or(AccelError::UnknownId { kind: "prototype", id: b.prototype })?;
        loaded.instances.push(accel.add_instance(proto, b.transform)?);
    }
    Ok(loaded)
}
