//! A tree as it stands in the scene: its supports and the hierarchy over their segments, the
//! component other kinds read (the sloth walks its supports).

use super::model::Tree;
use crate::foundation::dump::DumpState;
use crate::spatial::bvh::SegmentBvh;
use crate::spatial::segment::TaperedSegment;
use bevy::prelude::*;
use serde_json::{Map, Value, json};

/// A live tree: its supports and the hierarchy over their segments.
#[derive(Component, Debug, Clone)]
pub struct TreeBody {
    /// The supports.
    pub tree: Tree,
    /// Every segment of every support, for queries.
    pub bvh: SegmentBvh,
    /// The support each segment of `bvh` belongs to.
    pub segment_supports: Vec<usize>,
}

impl TreeBody {
    /// Where a point `along` (0 to 1) segment `segment` lies on its support, as a fraction of
    /// the support's length.
    pub fn fraction_along(&self, segment: usize, along: f32) -> f32 {
        let index = self.segment_supports[segment];
        let first = self.segment_supports.iter().position(|&s| s == index).unwrap_or(segment);
        let support = &self.tree.supports[index];
        let lengths: Vec<f32> = support.points.windows(2).map(|p| p[0].distance(p[1])).collect();
        let local = segment - first;
        let before: f32 = lengths[..local].iter().sum();
        (before + along * lengths[local]) / lengths.iter().sum::<f32>().max(f32::MIN_POSITIVE)
    }
}

impl DumpState for TreeBody {
    fn dump(&self, out: &mut Map<String, Value>) {
        let supports: Vec<Value> = self
            .tree
            .supports
            .iter()
            .enumerate()
            .map(|(index, s)| {
                json!({
                    "name": s.name,
                    "kind": s.kind.key(),
                    "gripped": self.tree.gripped(index),
                    "points": s.points.iter().map(|p| p.to_array()).collect::<Vec<_>>(),
                    "radii": s.radii,
                })
            })
            .collect();
        out.insert("supports".into(), json!(supports));
    }
}

impl TreeBody {
    /// The body of a built tree: its supports and the hierarchy over their segments.
    pub fn new(tree: Tree) -> Self {
        let (segment_supports, segments): (Vec<usize>, Vec<TaperedSegment>) = tree.segments().unzip();
        TreeBody { tree, bvh: SegmentBvh::new(segments), segment_supports }
    }
}
