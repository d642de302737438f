//! The `tree` entity kind: trunks and branches as chains of tapered segments, drawn as smooth
//! tubes with rounded tips, and the geometry queries the sloth and the editor need.
//!
//! | module | what it holds |
//! |---|---|
//! | [`kind`] | [`TreeKind`]: the tree built while checking, stood on the ground under it, spawned and saved; its panel |
//! | [`def`] | the `tree:` entry of a scene file and its checks |
//! | [`plugin`] | [`TreePlugin`] and its set [`TreeSystems`]: the live tree, picking, edits with undo, mesh write-back, dump |
//! | [`panel`] | the window's tree section: counts, the picked support and its editor |
//! | [`model`] | supports from their descriptions (polylines or forks), trunk or branch |
//! | [`body`] | [`TreeBody`]: a tree as it stands, the component other kinds read |
//! | [`mesh`] | the render mesh: tubes with parallel-transported rings and rounded tips |
//! | [`generate`] | the seeded tree and forest generator |
//! | [`edit`] | checked edits of a written-out tree |
//! | [`qsm`] | scanned trees' cylinder models read from TreeQSM, SimpleForest and aRchi files |
//!
//! The pure modules are tested (the queries against brute force) and benchmarked without a
//! world. Where the rules live: a support tilted more than 70 degrees from horizontal is a
//! trunk ([`model`]); a fork starts inside its parent at a fraction of its length ([`model`]).

pub mod body;
pub mod def;
pub mod edit;
pub mod generate;
pub mod kind;
pub mod mesh;
pub mod model;
pub mod panel;
pub mod plugin;
pub mod qsm;

pub use body::TreeBody;
pub use def::{SupportDef, TreeDef};
pub use generate::{GeneratorSettings, ScatterSettings};
pub use kind::TreeKind;
pub use model::{Shape, Support, SupportKind, SupportSpec, Tree, TreeError};
pub use plugin::{
    ChunkTrees, ScatteredTrees, SelectedSupport, TreePlugin, TreeSource, TreeSystems, edit_tree, undo_tree_edit,
};
