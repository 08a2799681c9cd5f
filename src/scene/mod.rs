//! What a frame is rendered of, shared by the passes, the effects and the
//! renderer: the [`view`] (camera, lighting, the GPU's view constants), the
//! tile [`shading`] rules and the display [`tonemap`].

pub mod effect;
pub mod graph;
pub mod params;
pub mod shading;
pub mod tonemap;
pub mod view;
