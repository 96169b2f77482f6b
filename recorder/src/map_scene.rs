//! The map as a scene on `/slam/map_scene`: each recorded map snapshot again, as one entity
//! per corner that Foxglove's 3D panel draws in the map frame.

use crate::corner_glyph::{arms, drawable, ellipse};
use crate::own::MapMessage;
use crate::scene::{
    Color, DELETE_MATCHING_ID, LINE_STRIP, LinePrimitive, Scene, SceneEntity, SceneEntityDeletion,
    SceneTopic, SceneUpdate,
};
use crate::stamp::Time;

/// A map corner's arms: orange.
pub const MAP_CORNER_COLOR: Color = Color::rgb(1.0, 0.55, 0.0);
/// Its covariance ellipse: the same, see-through.
pub const MAP_ELLIPSE_COLOR: Color = MAP_CORNER_COLOR.with_alpha(0.4);
/// Width of a map corner's arms, pixels.
const ARM_THICKNESS: f64 = 3.0;

/// The topic of the map's scenes.
#[derive(Debug)]
pub enum MapSceneTopic {}

impl SceneTopic for MapSceneTopic {
    const TOPIC: &'static str = "/slam/map_scene";
}

/// One map snapshot as a scene: an entity per corner, and deletions of the corners shown
/// before that this snapshot no longer has.
pub type MapScene = Scene<MapSceneTopic>;

/// The id of the entity of the snapshot's `index`th corner. A snapshot lists the best
/// particle's confirmed corners by their id in its map, without the ids: the rank stands in
/// for them, so a corner that stays is replaced in place, and every snapshot holds the whole
/// map, so what the scene shows is always exactly the snapshot.
pub fn corner_entity_id(index: usize) -> String {
    format!("corner {index}")
}

/// Turns map snapshots into scenes, remembering how many corner entities the last one
/// showed.
#[derive(Debug, Default)]
pub struct MapScenes {
    shown: usize,
}

impl MapScenes {
    /// The scene of `map`: its corners, and the deletion of every entity shown before that
    /// it does not replace (a corner gone from the map, or one it cannot draw).
    pub fn scene(&mut self, map: &MapMessage) -> MapScene {
        let stamp_ns = map.header.stamp_ns;
        let frame = map.header.frame_id();
        let mut entities = Vec::with_capacity(map.corners.len());
        let mut deletions = Vec::new();
        let delete = |index: usize| SceneEntityDeletion {
            timestamp: Time::from_ns(stamp_ns),
            kind: DELETE_MATCHING_ID,
            id: corner_entity_id(index),
        };
        for (index, observed) in map.corners.iter().enumerate() {
            let corner = &observed.corner;
            if !drawable(corner) {
                deletions.push(delete(index));
                continue;
            }
            let arms = LinePrimitive::new(
                LINE_STRIP,
                arms(corner).to_vec(),
                ARM_THICKNESS,
                MAP_CORNER_COLOR,
            );
            entities.push(SceneEntity::new(
                stamp_ns,
                frame,
                corner_entity_id(index),
                ellipse(corner, MAP_ELLIPSE_COLOR).into_iter().collect(),
                vec![arms],
            ));
        }
        deletions.extend((map.corners.len()..self.shown).map(delete));
        self.shown = map.corners.len();
        MapScene::new(SceneUpdate {
            deletions,
            entities,
        })
    }
}
