// Quantity direction_id (core/src/sensor/quantities/direction_id.rs): the unit reflected
// direction (rgb) and 1 + the id of what it meets (a). The clear value 0 marks the pixels
// that do not see the mirror, so a is every quantity's mask; ids are integers far below
// 2^24, exact in a float.
vec4 quantity_direction_id(PixelHit hit) {
    return vec4(hit.reflected, float(hit.id + 1u));
}
