// shared.glsl - every GPU-visible struct and constant. The structs are mirrored by
// engine/src/render/gpu.rs, and a test compares the offsets glslang gives these members with
// the Rust structs' offsets; every integer #define here is generated as a Rust constant by
// engine/build.rs (crate::shaders::shared), so it is written only once.
//
// Spaces: "world" on the GPU is world space translated so that the mirror centre is the
// origin (render origin), which keeps f32 precise for scenes far from (0,0,0).
// View space is x right, y down, z forward: Vulkan's framebuffer axes (docs/conventions.md).
#ifndef SHARED_GLSL
#define SHARED_GLSL

// Texture slots bound at set 0, binding 4 (unused slots hold a 1x1 white texel).
#define MAX_TEXTURES 16

// MaterialData.kind values (core/src/scene MaterialKind).
#define MATERIAL_COLOR 0u
#define MATERIAL_CHECKER 1u
#define MATERIAL_GRID 2u
#define MATERIAL_TEXTURE 3u
#define MATERIAL_DIRECTION 4u

// Per-frame constants.
struct FrameData {
    vec4 light_dir_ambient; // xyz: unit vector towards the light; w: ambient fraction
    vec4 mirror;            // xyz: the mirror's viewpoint (render space: 0, render space is
                            // centred on it); w: the radius about it that holds the mirror (m)
    uvec4 flags;            // x: 1 when the directional light is on; y: LOOKUP_FROM_*;
                            // z, w: the distance lookup's linear and secant steps
    vec4 room_min;          // xyz: the room box's low corner (render space)
    vec4 room_max;          // xyz: its high corner
    vec4 cube;              // x, y: the cube faces' near and far planes (m), to turn their
                            // reverse-Z depth back into distances (distance_search.glsl);
                            // z: the most samples a pixel's footprint filter takes along its
                            // long side, >= 1 ([cube] anisotropy, footprint_filter.glsl)
    uvec4 mirror_shape;     // x: MIRROR_SPHERE or MIRROR_QUADRIC (core/src/mirror)
    vec4 mirror_quadric;    // MIRROR_QUADRIC, axis +Y through the viewpoint (mirror.xyz): the
                            // surface x^2 + z^2 + a s^2 + b s = 0, s the height above the
                            // vertex; x, y: a, b; z: the vertex's height above the viewpoint;
                            // w: the rim's height, where a flat disc closes the mirror
    vec4 mirror_extent;     // x: the rim's radius; y: the lowest height of the mirror's body;
                            // z, w: the rim's and that lowest height above the vertex
                            // (subtracted in f64: a flat rim is micrometres above it)
    vec4 cube_centre;       // xyz: where the cube map is rendered from (render space: the
                            // scene's cube.offset from the viewpoint, 0 by default); every
                            // lookup's direction is from here
};

// FrameData.mirror_shape.x: how mirror_hit finds the mirror (quadric.glsl, sphere.glsl).
#define MIRROR_SPHERE 0u  // a sphere of radius mirror.w about mirror.xyz
#define MIRROR_QUADRIC 1u // a quadric of revolution cut at its rim: the central mirrors

// FrameData.flags.y: the cube-map direction a lookup starts from (mirror.glsl lookup_at). Each
// lookup's own technique is its shader (render/lookups: a lookup's `start`); only this choice
// is shared, so a new lookup adds no code here.
#define LOOKUP_FROM_REFLECTION 0u // the reflected direction itself (the thesis's plain lookup)
#define LOOKUP_FROM_ROOM_BOX 1u   // from the cube's centre to where the reflected ray leaves the room box

// distance-exact's tally (trace_tally.glsl, render/lookups/tally.rs): a uvec2 (fragments,
// traced) per view and pass, at view_index * TALLY_PASSES + the pass.
#define TALLY_PASSES 2u
#define TALLY_PASS_COLOUR 0u
#define TALLY_PASS_DIRECTION 1u

// One camera: a cube face or a view. dir(ndc) = ray_forward + ndc.x*ray_right + ndc.y*ray_down,
// from origin(ndc) = eye + ndc.x*origin_right + ndc.y*origin_down (mirror.glsl view_ray and
// view_origin): a pinhole has origin_* 0, an orthographic view (a paraboloid's telecentric
// sensor) ray_right and ray_down 0.
struct ViewData {
    mat4 world_to_clip;  // reverse-Z perspective or orthographic: near -> depth 1, far -> 0
    vec4 eye;            // xyz: camera position (render space)
    vec4 ray_right;      // xyz: right * tan(half fov x)
    vec4 ray_down;       // xyz: down * tan(half fov y)
    vec4 ray_forward;    // xyz: unit forward
    vec4 viewport;       // x, y, width, height in framebuffer pixels
    vec4 origin_right;   // xyz: right * half the orthographic image's width (m)
    vec4 origin_down;    // xyz: down * half its height (m)
};

// One drawable object.
struct ObjectData {
    mat4 model_to_world;
    mat4 normal_to_world; // inverse transpose of model_to_world
    uvec4 material;       // x: index into materials[]
};

// One material (see materials.glsl for what each kind computes).
struct MaterialData {
    uvec4 kind_texture; // x: MATERIAL_*, y: texture slot
    vec4 color_a;       // rgb: colour / checker a / grid background / texture tint
    vec4 color_b;       // rgb: checker b / grid line colour
    vec4 params;        // x: tiles per uv unit, y: grid line width (fraction of a cell)
};

// One point at which materials_check.comp evaluates a material: what a scene fragment sees.
struct MaterialSample {
    vec4 position; // xyz: render space
    vec4 normal;   // xyz: interpolated normal (shade() normalizes it)
    vec4 uv;       // xy: texture coordinate
};

// materials_check.comp's push constants: samples first .. first + count, all of one material
// (so that the texture index is dynamically uniform, as in scene.frag).
#define CHECK_PUSH_CONSTANTS \
    layout(push_constant) uniform CheckPush { uint first; uint count; uint material; uint pad; } check

// cube_mips.comp's push constants: the box of level m to write (origin, size, in texels of
// that level) on faces first_face onwards, one face a layer of the dispatch.
#define MIP_BOX_PUSH_CONSTANTS \
    layout(push_constant) uniform MipBox { ivec2 origin; ivec2 size; int first_face; } box

// Push constants: which view and which object a draw uses; which cube faces a layered pass
// renders (bit f set: face f; the other faces keep their contents).
#define PUSH_CONSTANTS \
    layout(push_constant) uniform Push { uint view_index; uint object_index; uint face_mask; uint pad; } push

// The id cube's value where no drawable was drawn (its clear value), and the sensor's id for
// "nothing": drawables are numbered walls 0..6 (face order), then objects 6 + i.
#define OBJECT_NONE 4294967295u

// Instanced cube fill: gl_InstanceIndex = object << INSTANCE_FACE_BITS | face.
#define INSTANCE_FACE_BITS 3u

// Entries in the bvh lookup's walk stack (bvh_cwbvh.glsl, core/src/bvh/cwbvh), which walks
// both levels: each node level leaves at most one entry (the rest of the group it came from),
// entering an object two (the rest of its node and object groups), and a mesh's tree is
// walked above the top level's entries, so the top level's depth plus the deepest mesh's
// must fit. Walks that need more are refused when the trees are built; the benchmark scenes
// need at most 11 (heavy.toml: a top level 6 deep, meshes 5; core/src/bvh/tests.rs prints
// them).
#define BVH_STACK_SIZE 32u

// The same for the four-wide layout (bvh_bvh4.glsl, core/src/bvh/bvh4): each node the walk
// passes leaves the children it met but did not go on with (at most three of its four), each
// with its distance. The benchmark scenes need at most 33 (many-objects.toml's 2,000 objects).
// 64 entries of 8 bytes: 512 bytes an invocation.
#define BVH4_STACK_SIZE 64u

// How many times a ray from far away is moved near an object before its tree is walked
// (bvh.glsl model_ray; core/src/reference/intersect.rs MODEL_RAY_MOVES says why three).
#define MODEL_RAY_MOVES 3u

// The least gap it leaves before the ball, as 2^-N of the model's units (MODEL_RAY_GAP).
#define MODEL_RAY_GAP_EXPONENT 12u

// How far past a wall the traced lookups search the objects, as 2^-ON_WALL_SLACK_EXPONENT of
// the ray's scale (|o| + t), so that an object lying on a wall's plane wins the tie against the
// wall (traced_surface.glsl `objects_limit`; core/src/reference/room.rs `objects_limit` says
// why this much).
#define ON_WALL_SLACK_EXPONENT 19u

// The ray-query lookups' instance masks: the walls' instances, and the objects', which
// ray_query.glsl asks alone over a sliver about a wall the ray meets (an object on the wall's
// plane wins the tie).
#define RAY_MASK_WALLS 1u
#define RAY_MASK_OBJECTS 2u

// The camera views (observer, sensor, the pair's two) follow the six cube faces in the views
// block: a pretraced lookup keeps one record a camera-view pixel, in view order from the first
// (pretrace.glsl; engine/src/render/resources.rs VIEW_OBSERVER).
#define FIRST_CAMERA_VIEW 6u
#define CAMERA_VIEWS 4u
// Bytes of one pretraced pixel's record (pretrace.glsl's TracedPixel), and the side of the
// pretrace's square workgroup (trace_view.comp).
#define TRACED_PIXEL_BYTES 32u
#define TRACE_GROUP_SIDE 8u
// The side of cube_mips.comp's square workgroup.
#define MIP_GROUP_SIDE 8u

// footprint_mark.comp's push constants: the view whose pixels it marks, the cube's face side
// (texels at level 0) and mip levels, and the tiles each face side is cut into
// (tiles_per_side of tile_side texels); and the side of its square workgroup. The marks are
// one bit a tile, face after face, row after row (footprint_marks.glsl).
#define FOOTPRINT_PUSH_CONSTANTS \
    layout(push_constant) uniform FootprintPush { uint view_index; uint face_size; uint levels; uint tile_side; uint tiles_per_side; uint pad0; uint pad1; uint pad2; } marking
#define FOOTPRINT_GROUP_SIDE 8u

// Descriptor set 0: the scene. Set 1: the environment cube (views only).
#define SCENE_BINDINGS \
    layout(set = 0, binding = 0) uniform FrameBlock { FrameData frame; }; \
    layout(set = 0, binding = 1, std430) readonly buffer ViewBlock { ViewData views[]; }; \
    layout(set = 0, binding = 2, std430) readonly buffer ObjectBlock { ObjectData objects[]; }; \
    layout(set = 0, binding = 3, std430) readonly buffer MaterialBlock { MaterialData materials[]; }; \
    layout(set = 0, binding = 4) uniform sampler2D textures[MAX_TEXTURES]

#endif
