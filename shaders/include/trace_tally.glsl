// trace_tally.glsl - counts, per mirror draw, the fragments a lookup shaded and the rays among
// them it traced (render/lookups/tally.rs reads them back). Each view and pass has its own
// slot, so the frame's draws never write the same counter. Define TALLY_BINDING (set 1) and
// TALLY_PASS (TALLY_PASS_COLOUR or TALLY_PASS_DIRECTION) and declare PUSH_CONSTANTS first.
#ifndef TRACE_TALLY_GLSL
#define TRACE_TALLY_GLSL

layout(set = 1, binding = TALLY_BINDING, std430) buffer TraceTally {
    uvec2 tally[];
};

// One mirror fragment shaded; `traced`: its ray was traced.
void count_fragment(bool traced) {
    uint slot = push.view_index * TALLY_PASSES + TALLY_PASS;
    atomicAdd(tally[slot].x, 1u);
    if (traced) {
        atomicAdd(tally[slot].y, 1u);
    }
}

#endif
