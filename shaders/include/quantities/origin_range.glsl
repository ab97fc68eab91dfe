// Quantity origin_range (core/src/sensor/quantities/origin_range.rs): the mirror point
// (render space, rgb) and the range along the reflected ray (a).
vec4 quantity_origin_range(PixelHit hit) {
    return vec4(hit.mirror_point, hit.range);
}
