//! A scan's features as a scene on `/perception/scene`: the fitted lines and the corners,
//! in the scan's frame, drawn by Foxglove's 3D panel where the sensor was at the scan.

use ipc_types::Features;

use crate::corner_glyph::{arms, drawable, ellipse};
use crate::scene::{
    Color, LINE_LIST, LinePrimitive, Scene, SceneEntity, SceneTopic, SceneUpdate, point,
};

/// A features scene is recorded at most once per this much data time (every twentieth scan
/// of a 40 Hz sensor): the features are recorded whole on `/perception/features` at every
/// scan, and the scene is for the eye: at every scan the scenes would add several per cent
/// to a recording that is already large, at two a second next to nothing.
pub const FEATURES_SCENE_PERIOD_NS: u64 = 500_000_000;

/// The fitted lines: green.
pub const LINE_COLOR: Color = Color::rgb(0.1, 0.8, 0.1);
/// The corners' arms: blue.
pub const FEATURE_CORNER_COLOR: Color = Color::rgb(0.0, 0.6, 1.0);
/// Their covariance ellipses: the same, see-through.
pub const FEATURE_ELLIPSE_COLOR: Color = FEATURE_CORNER_COLOR.with_alpha(0.35);
/// Width of the lines and arms, pixels.
const THICKNESS: f64 = 2.0;

/// The entity of a scan's lines; each scene replaces the last one's.
pub const LINES_ENTITY: &str = "lines";
/// The entity of a scan's corners.
pub const CORNERS_ENTITY: &str = "corners";

/// The topic of the features' scenes.
#[derive(Debug)]
pub enum FeaturesSceneTopic {}

impl SceneTopic for FeaturesSceneTopic {
    const TOPIC: &'static str = "/perception/scene";
}

/// One scan's features as a scene: the entity of its lines and the entity of its corners.
pub type FeaturesScene = Scene<FeaturesSceneTopic>;

/// The scene of `features`: each line as a segment between the ends of its points, each
/// corner as its arms and its covariance ellipse; what is not finite is left out.
pub fn features_scene(features: &Features) -> FeaturesScene {
    let stamp_ns = features.header.stamp_ns;
    let frame = features.header.frame_id();
    let segments = features
        .lines()
        .iter()
        .filter(|l| l.start.iter().chain(&l.end).all(|v| v.is_finite()))
        .flat_map(|l| [point(l.start[0], l.start[1]), point(l.end[0], l.end[1])])
        .collect();
    let lines = SceneEntity::new(
        stamp_ns,
        frame,
        LINES_ENTITY.to_owned(),
        Vec::new(),
        vec![LinePrimitive::new(
            LINE_LIST, segments, THICKNESS, LINE_COLOR,
        )],
    );
    let corners: Vec<_> = features.corners().iter().filter(|c| drawable(c)).collect();
    let corner_arms = corners
        .iter()
        .flat_map(|c| {
            let [first, tip, second] = arms(c);
            [first, tip, tip, second]
        })
        .collect();
    let corners = SceneEntity::new(
        stamp_ns,
        frame,
        CORNERS_ENTITY.to_owned(),
        corners
            .iter()
            .filter_map(|c| ellipse(c, FEATURE_ELLIPSE_COLOR))
            .collect(),
        vec![LinePrimitive::new(
            LINE_LIST,
            corner_arms,
            THICKNESS,
            FEATURE_CORNER_COLOR,
        )],
    );
    FeaturesScene::new(SceneUpdate {
        deletions: Vec::new(),
        entities: vec![lines, corners],
    })
}

/// Picks the scans whose features are drawn: at most one per [`FEATURES_SCENE_PERIOD_NS`]
/// of data time.
#[derive(Debug, Default)]
pub struct FeaturesScenes {
    last_ns: Option<u64>,
}

impl FeaturesScenes {
    /// The scene of `features`, or `None` when the last one drawn is too recent.
    pub fn scene(&mut self, features: &Features) -> Option<FeaturesScene> {
        let stamp_ns = features.header.stamp_ns;
        if self
            .last_ns
            .is_some_and(|last| stamp_ns < last.saturating_add(FEATURES_SCENE_PERIOD_NS))
        {
            return None;
        }
        self.last_ns = Some(stamp_ns);
        Some(features_scene(features))
    }
}
