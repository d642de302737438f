//! System tests: the real plugins, headless, on scenes from disk, checked through the state
//! dump and the framebuffer; one module per domain, in one binary so that they build once and
//! run in parallel.

mod ar;
mod ar_sources;
mod canopy;
mod common;
mod controls;
mod elastic;
mod muscle;
mod saving;
mod scene;
mod shape;
mod sloth;
mod sloth_debug;
mod soft_body;
mod terrain;
mod tree;
mod view;
mod world;
