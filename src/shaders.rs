//! The generated shader bank: SPIR-V, stage, workgroup size, binding and
//! specialization constants and push-constant size per shader, and the size
//! of every named GLSL struct (see build.rs).
#![allow(clippy::all)]
include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
