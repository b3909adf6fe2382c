//! A commit's changes applied to the persistent tree at once ([`StaticBvh::apply`]): removals,
//! then a rebuild, or a block per added mesh and one overlay over every live block, re-braided or
//! relinked.

use std::sync::Arc;

use super::{MeshEntry, StaticBvh, StaticUpdate};
use crate::accel::bvh::triangle::{extract, Tri};
use crate::accel::{AccelError, StaticId};
use crate::geometry::TriangleMesh;

impl StaticBvh {
    /// Applies a batch of changes the way a commit should: removals first, then either one
    /// rebuild (an empty tree, or a removal from a shared block), or a block per added mesh and
    /// one new overlay over every live block: re-braided ([`super::rebraid`]), or relinked
    /// ([`Self::relink`]) once the new triangles pass [`Self::rebuild_fraction`]. Unknown ids
    /// in `removes` are ignored; an added id that is present replaces that mesh.
    pub fn apply(
        &mut self,
        removes: &[StaticId],
        adds: &[(StaticId, &TriangleMesh)],
    ) -> Result<StaticUpdate, AccelError> {
        for (_, m) in adds {
            m.validate()?;
        }
        let mut skipped = 0;
        let extracted = adds
            .iter()
            .map(|(id, m)| {
                let (tris, s) = extract(m, id.0);
                skipped += s;
                (*id, tris)
            })
            .collect();
        let mut update = self.apply_extracted(removes, extracted);
        update.skipped_triangles += skipped;
        Ok(update)
    }

    /// [`Self::apply`] with triangles already extracted (skipped ones are not counted here).
    pub(crate) fn apply_extracted(
        &mut self,
        removes: &[StaticId],
        adds: Vec<(StaticId, Vec<Tri>)>,
    ) -> StaticUpdate {
        let mut update = StaticUpdate::default();
        let mut need_rebuild = false;
        let mut changed = !adds.is_empty();
        let replaced = adds.iter().map(|(id, _)| id);
        for id in removes.iter().chain(replaced) {
            // The entry goes now; the tree is rebuilt or re-braided without it below.
            if let Some(e) = self.forget(*id) {
                changed = true;
                need_rebuild |= e.shared && e.triangles > 0;
            }
        }
        if !changed {
            return update;
        }
        let added: usize = adds.iter().map(|(_, t)| t.len()).sum();
        let budget = self.rebuild_fraction * self.state.rebuilt_triangles as f32;
        if need_rebuild || self.state.triangles == 0 {
            let mut tris = self.live_tris();
            let meshes = Arc::make_mut(&mut self.state.meshes);
            for (id, t) in adds {
                meshes.insert(id, MeshEntry { block: u32::MAX, shared: true, triangles: t.len() });
                if tris.is_empty() {
                    // The first mesh of an empty tree is moved, not copied.
                    tris = t;
                } else {
                    tris.extend(t);
                }
            }
            self.rebuild_from(tris);
            update.rebuilt = true;
            update.built_triangles = self.state.triangles;
            return update;
        }
        let over_budget = (self.state.inserted_since_rebuild + added) as f32 > budget;
        let mut blocks = self.live_blocks();
        for (id, t) in adds {
            update.built_triangles += t.len();
            blocks.extend(self.add_mesh(id, t));
        }
        let merged = if over_budget {
            update.relinked = true;
            self.relink(blocks)
        } else {
            (!self.braid_or_rebuild(&blocks)).then_some(0)
        };
        match merged {
            Some(merged) => update.built_triangles += merged,
            None => {
                update.rebuilt = true;
                update.built_triangles = self.state.triangles;
            }
        }
        update
    }
}
