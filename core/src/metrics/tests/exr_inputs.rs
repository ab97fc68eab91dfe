//! Bad and unusual OpenEXR inputs: refused with what is wrong (not an EXR, cut short, a header
//! the format forbids, a layer too large), and images whose windows start apart.

use super::*;

/// Bad EXR inputs are refused with what is wrong: not an EXR, truncated, a header that claims
/// a layer larger than [`MAX_INPUT_SIDE_PX`] (refused from the header, before its pixels would
/// be allocated: 100,000² RGBA f32 is 160 GB), and a folder.
#[test]
fn bad_exr_inputs_say_what_is_wrong() {
    let dir = temp_dir("bad-exr");
    let good = dir.join("good.exr");
    crate::output::write_exr(&good, &gradient(4, 3)).unwrap();
    let bytes = std::fs::read(&good).unwrap();
    let cases = [
        (
            "png.exr",
            b"\x89PNG\r\n\x1a\n not an exr".to_vec(),
            "not an OpenEXR image",
        ),
        (
            "truncated.exr",
            bytes[..bytes.len() / 2].to_vec(),
            "truncated",
        ),
        (
            "huge.exr",
            huge_data_window(&bytes),
            "at most 16384 px a side",
        ),
        // Shorter than the magic number: not an EXR at all, not a truncated one.
        ("hi.exr", b"hi\n".to_vec(), "not an OpenEXR image"),
        // The crate read this as the 4 x 3 image it was (a window's size taken as the
        // distance between its corners); one inverted on x by 1 it called damaged data.
        (
            "inverted.exr",
            data_window(&bytes, [3, 0, 0, 2]),
            "inverted window, which OpenEXR does not allow (dataWindow: xMax 0 is less than \
             xMin 3)",
        ),
        (
            "inverted-by-one.exr",
            data_window(&bytes, [0, 0, -1, 2]),
            "dataWindow: xMax -1 is less than xMin 0",
        ),
    ];
    for (name, data, must_say) in cases {
        let path = dir.join(name);
        std::fs::write(&path, data).unwrap();
        let e = read_exr(&path).unwrap_err().to_string();
        assert!(e.contains(name) && e.contains(must_say), "{name}: {e}");
    }
    // A layer without colour (the sensor's range) is named by its channels.
    let range = dir.join("range.exr");
    let layer = vec![("range", crate::image::exr::Samples::F32(vec![1.0; 12]))];
    let file = std::fs::File::create(&range).unwrap();
    crate::image::exr::encode_channels(std::io::BufWriter::new(file), (4, 3), layer).unwrap();
    let e = read_exr(&range).unwrap_err().to_string();
    assert!(
        e.contains("holds no colour image (channels R, G, B) but range"),
        "{e}"
    );
    let e = read_exr(&dir).unwrap_err().to_string();
    assert!(e.contains("not a regular file"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Images whose data windows start at different pixels are refused, naming both corners:
/// compared pixel for pixel they would be compared shifted (a window at (100, 200) compared
/// as identical to the same pixels at (0, 0)). Windows that start together, anywhere, are
/// compared.
#[test]
fn images_whose_windows_start_apart_are_refused() {
    let dir = temp_dir("origins");
    let at_zero = dir.join("zero.exr");
    crate::output::write_exr(&at_zero, &gradient(16, 8)).unwrap();
    let shifted = dir.join("shifted.exr");
    write_exr_at(&shifted, &gradient(16, 8), (100, 200));
    let e = read_inputs(&at_zero, &shifted, None).err().unwrap();
    assert!(matches!(e, MetricsError::OriginMismatch { .. }), "{e}");
    let said = e.to_string();
    assert!(
        said.contains("zero.exr starts at (0, 0), ") && said.contains("shifted.exr at (100, 200)"),
        "{said}"
    );
    // Both shifted alike: compared (the same pixels).
    let also = dir.join("also.exr");
    write_exr_at(&also, &gradient(16, 8), (100, 200));
    let read = read_inputs(&shifted, &also, None).unwrap();
    assert_eq!(read.test, read.reference);
    // A mask's window too.
    let e = read_inputs(&shifted, &also, Some(&at_zero)).err().unwrap();
    assert!(matches!(e, MetricsError::OriginMismatch { .. }), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `image` as an EXR whose data window starts at `origin`, as a tool that crops writes it.
fn write_exr_at(path: &std::path::Path, image: &RgbaImage, (x, y): (i32, i32)) {
    use ::exr::prelude::*;
    let attributes = LayerAttributes {
        layer_position: Vec2(x, y),
        ..LayerAttributes::named("")
    };
    let size = (image.width as usize, image.height as usize);
    let pixels = |p: Vec2<usize>| {
        let [r, g, b, a] = image.pixels[p.y() * size.0 + p.x()];
        (r, g, b, a)
    };
    let channels = SpecificChannels::rgba(pixels);
    let layer = Layer::new(size, attributes, Encoding::UNCOMPRESSED, channels);
    Image::from_layer(layer).write().to_file(path).unwrap();
}

/// `bytes` (a small EXR) with its data window's corner moved to (99999, 99999).
fn huge_data_window(bytes: &[u8]) -> Vec<u8> {
    data_window(bytes, [0, 0, 99_999, 99_999])
}

/// `bytes` (a small EXR) with its data window (xMin, yMin, xMax, yMax) replaced.
fn data_window(bytes: &[u8], corners: [i32; 4]) -> Vec<u8> {
    let key = b"dataWindow\0box2i\0";
    let at = bytes
        .windows(key.len())
        .position(|w| w == key)
        .expect("a dataWindow attribute")
        + key.len()
        + 4; // the attribute's size field
    let mut out = bytes.to_vec();
    // box2i: xMin, yMin, xMax, yMax as little-endian i32.
    for (k, c) in corners.iter().enumerate() {
        out[at + 4 * k..at + 4 * k + 4].copy_from_slice(&c.to_le_bytes());
    }
    out
}
