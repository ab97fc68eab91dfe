//! Bad and unusual OpenEXR inputs: refused with what is wrong (not an EXR, cut short, a header
//! the format forbids, a layer too large, a part not read cut short), and images whose
//! windows start apart.

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
    // And one with no channel at all (its channel list emptied) says so.
    let empty = dir.join("empty.exr");
    std::fs::write(&empty, without_channels(&bytes)).unwrap();
    let e = read_exr(&empty).unwrap_err().to_string();
    assert!(
        e.contains("empty.exr")
            && e.contains("holds no colour image (channels R, G, B) but no channel at all"),
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

/// A two-part file cut short in its second part is refused, though the colour part read is
/// whole: the crate reads only that part's chunks, and read it as whole. Cut in a chunk's
/// pixels or before a chunk begins, both are said with where, the second part in scan lines
/// or in tiles; the whole files are read.
#[test]
fn a_multi_part_file_cut_short_in_a_part_not_read_is_refused() {
    use ::exr::prelude::*;
    let dir = temp_dir("cut-parts");
    let size = Vec2(8, 64);
    // The range part's chunks are the file's last: 64 lines of 8 floats (44 bytes each with
    // their part number, line and size), or 8 tiles of 8 x 8 (280 bytes each with their
    // part number, four coordinates and size).
    let lines = Encoding::UNCOMPRESSED;
    let tiles = Encoding {
        blocks: Blocks::Tiles(Vec2(8, 8)),
        ..Encoding::UNCOMPRESSED
    };
    let cases = [
        (
            lines,
            "lines",
            [(10, "chunk 64 of 64"), (100, "chunk 62 of 64")],
        ),
        (
            tiles,
            "tiles",
            [(10, "chunk 8 of 8"), (300, "chunk 7 of 8")],
        ),
    ];
    for (encoding, blocks, cuts) in cases {
        let colour = Layer::new(
            size,
            LayerAttributes::named("colour"),
            Encoding::UNCOMPRESSED,
            SpecificChannels::rgba(|p: Vec2<usize>| (p.x() as f32, p.y() as f32, 0.5f32, 1f32)),
        );
        let range = Layer::new(
            size,
            LayerAttributes::named("range"),
            encoding,
            SpecificChannels::build()
                .with_channel("Z")
                .with_pixel_fn(|p: Vec2<usize>| (p.y() as f32,)),
        );
        let whole = dir.join(format!("{blocks}.exr"));
        (Image::empty(ImageAttributes::new(IntegerBounds::from_dimensions(size))))
            .with_layer(colour)
            .with_layer(range)
            .write()
            .to_file(&whole)
            .unwrap();
        let read = read_exr(&whole).unwrap();
        assert_eq!((read.width, read.height), (8, 64));
        let bytes = std::fs::read(&whole).unwrap();
        // Its first bytes alone, as a large file's are read for its size, are a header
        // whose chunks lie further on, not a file cut short.
        let head = &bytes[..bytes.len() / 2];
        let sized = super::read::size_from_head(&whole, head, true).unwrap();
        assert_eq!(sized, Some((8, 64)), "{blocks}");
        for (cut, chunk) in cuts {
            let name = format!("{blocks}-cut-{cut}.exr");
            let path = dir.join(&name);
            std::fs::write(&path, &bytes[..bytes.len() - cut]).unwrap();
            let e = read_exr(&path).unwrap_err().to_string();
            assert!(
                e.contains(&name) && e.contains("truncated: part 2 of 2, ") && e.contains(chunk),
                "{name}: {e}"
            );
        }
    }
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

/// `bytes` (a small EXR) with its channel list emptied (the list's terminating null alone);
/// the pixel data after it is left as it was, so only the header reads.
fn without_channels(bytes: &[u8]) -> Vec<u8> {
    let key = b"channels\0chlist\0";
    let at = bytes
        .windows(key.len())
        .position(|w| w == key)
        .expect("a channels attribute")
        + key.len();
    let size = i32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
    let mut out = bytes[..at].to_vec();
    out.extend(1i32.to_le_bytes());
    out.push(0);
    out.extend(&bytes[at + 4 + size..]);
    out
}
