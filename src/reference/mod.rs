//! CPU references, one per pass, sharing no code with the GPU path beyond
//! its inputs: tests and benches compare each pass against its twin here.

pub mod atmosphere;
pub mod bintree_cut;
pub mod classify;
pub mod emitted_cut;
pub mod finest;
pub mod grass;
#[cfg(feature = "bench")]
pub mod image_metric;
pub mod lod_map;
pub mod occlusion;
pub mod octahedral;
pub mod raycast;
pub mod sector_data;
pub mod sun_shadow;
pub mod tonemap;
pub mod traverse;
pub mod vt_feedback;

pub use classify::{classify_tiles_cpu, plane_tiles_cpu};
pub use finest::FinestSurface;
#[cfg(feature = "bench")]
pub use image_metric::{flip_magma, flip_map, flip_stats, FlipStats};
pub use lod_map::lod_map_cpu;
pub use raycast::{HeightBounds, RayCaster, RaycastConfig, ReferenceImage, Trace};
pub use sector_data::{sample_height_cpu, sector_data_cpu};
pub use traverse::{traverse_cpu, wanted_finer_cpu};
