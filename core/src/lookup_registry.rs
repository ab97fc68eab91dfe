//! The registry of mirror lookups: one entry per lookup, read in two places.
//!
//! - The scene makes its [`crate::scene::Lookup`] enum from it: the name a scene file, the CLI
//!   and every report use. The scene has no Vulkan, so it reads only the variant, its name and
//!   its doc.
//! - The renderer makes its table of plug-ins from it (`render::lookups`): what each lookup
//!   needs from the device, its pass, its shaders and its rungs in the benchmark's ladder.
//!
//! A new lookup is its plug-in module under `render/lookups/`, its shaders, and one entry
//! here; everything that lists lookups (the CLI's `--lookup`, `specchio info`, the ladder,
//! the scene format, the Python package) iterates what these make. The order is the order
//! they are listed in; the first is the default.
//!
//! An entry: the variant's doc, then `Variant = "name" => plug-in;`. The plug-in is a path
//! from `render::lookups`, read only where the renderer expands the registry (a macro's
//! tokens are resolved where it is expanded, so this module imports nothing).

/// Expands `$then! { entries }` with every lookup's entry, in order. Exported because the
/// renderer, which expands it into its plug-in table, is another crate (`specchio`).
#[doc(hidden)]
#[macro_export]
macro_rules! with_lookups {
    ($then:ident) => {
        $then! {
            /// The thesis: look up the reflected direction R itself (exact only for an
            /// environment infinitely far away).
            Plain = "plain" => cube::PLAIN;
            /// Parallax-corrected: intersect the reflected ray from the mirror point with the
            /// room's box and look up the direction from the cube's centre to that point
            /// (exact for an empty box room, up to texel sampling).
            Box = "box" => cube::BOX;
            /// Exact: the reflected ray is traced through the scene on the GPU (ray queries);
            /// no cube map.
            RayQuery = "ray-query" => ray_query::RayQuery;
            /// Distance-searched: the reflected ray is marched through the cube's own depth
            /// (each texel's distance from the cube's centre) and the colour is looked up
            /// where it meets it (Szirmay-Kalos et al. 2005). Exact for surfaces the cube's
            /// centre sees.
            Distance = "distance" => distance::Distance;
            /// Distance-searched, with the exact ray for the rays the search cannot resolve:
            /// where it crossed a jump in the stored distance that was not a hit (the ray
            /// passed behind an occluder, as seen from the cube's centre) or found nothing,
            /// the reflected ray is traced (ray queries). Exact wherever it falls back;
            /// `distance` elsewhere.
            DistanceExact = "distance-exact" => distance_exact::DistanceExact;
            /// Exact on any device: the reflected ray is traced through a BVH of our own in
            /// the mirror's shader (storage buffers, no extension); no cube map.
            Bvh = "bvh" => bvh::Bvh;
        }
    };
}

pub use crate::with_lookups;
