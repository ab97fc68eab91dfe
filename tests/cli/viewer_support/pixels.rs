//! The window's pixels as the X server holds them, and what the tests ask of them.

use std::time::{Duration, Instant};

use super::Xvfb;

/// The pixels window `id` shows on `x`, as the X server holds them (RGB, rows top to
/// bottom): what a person sees, whatever the viewer's own screenshot would say.
pub fn window_pixels(x: &Xvfb, id: &str) -> (u32, u32, Vec<u8>) {
    use x11rb::connection::Connection;
    use x11rb::protocol::xproto::{ConnectionExt, ImageFormat, ImageOrder};
    let (connection, _) = x11rb::connect(Some(&x.display)).expect("the X server answers");
    let window: u32 = id.trim().parse().expect("a window id");
    let geometry = (connection.get_geometry(window).unwrap().reply()).expect("the window's size");
    let (w, h) = (geometry.width, geometry.height);
    let image = connection
        .get_image(ImageFormat::Z_PIXMAP, window, 0, 0, w, h, !0)
        .unwrap()
        .reply()
        .expect("the window's pixels");
    // Xvfb's 24-bit screen: 32 bits a pixel, least significant byte first, blue in the low
    // byte (the root visual's masks); rows unpadded at 32 bits a pixel.
    let setup = connection.setup();
    let screen = &setup.roots[0];
    let bits = (setup.pixmap_formats.iter())
        .find(|f| f.depth == image.depth)
        .map(|f| f.bits_per_pixel);
    let visual = (screen.allowed_depths.iter())
        .flat_map(|d| &d.visuals)
        .find(|v| v.visual_id == screen.root_visual)
        .expect("the root visual");
    assert_eq!(
        (image.depth, bits),
        (24, Some(32)),
        "a 24-bit screen, 32 bits a pixel"
    );
    assert_eq!(setup.image_byte_order, ImageOrder::LSB_FIRST, "byte order");
    assert_eq!(visual.blue_mask, 0xff, "blue in the low byte");
    assert_eq!(visual.red_mask, 0xff_0000, "red in the third byte");
    let rgb = (image.data.chunks_exact(4))
        .flat_map(|p| [p[2], p[1], p[0]])
        .collect();
    (u32::from(w), u32::from(h), rgb)
}

/// Asks `found` every 50 ms until it finds something, for at most 30 s (a held frame lasts
/// 60 s): what it found, or a failure naming `what`.
pub fn eventually<T>(what: &str, found: impl FnMut() -> Option<T>) -> T {
    eventually_within(what, Duration::from_secs(30), found)
}

/// [`eventually`] for at most `budget`: a guard against a hang, not a time asked of the
/// viewer (tests time nothing).
pub fn eventually_within<T>(
    what: &str,
    budget: Duration,
    mut found: impl FnMut() -> Option<T>,
) -> T {
    let start = Instant::now();
    while start.elapsed() < budget {
        if let Some(t) = found() {
            return t;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    panic!("never saw {what} ({} s)", budget.as_secs());
}

/// Channels (of RGB pixels) above 16 of 255: the window is not black.
pub fn lit(rgb: &[u8]) -> usize {
    rgb.iter().filter(|&&c| c > 16).count()
}

/// Pixels that differ by more than 8 in some channel between two images of one size.
pub fn changed(a: &[u8], b: &[u8]) -> usize {
    if a.len() != b.len() {
        return a.len().max(b.len()) / 3;
    }
    (a.chunks_exact(3).zip(b.chunks_exact(3)))
        .filter(|(p, q)| p.iter().zip(q.iter()).any(|(x, y)| x.abs_diff(*y) > 8))
        .count()
}

/// The window's pixels once they are lit (not black) and settled (the same twice, 500 ms
/// apart): the view the window shows while nothing new comes.
pub fn settled_view(x: &Xvfb, id: &str) -> (u32, u32, Vec<u8>) {
    settled_view_within(x, id, Duration::from_secs(30))
}

/// [`settled_view`], looked for at most `budget`.
pub fn settled_view_within(x: &Xvfb, id: &str, budget: Duration) -> (u32, u32, Vec<u8>) {
    eventually_within("a settled view in the window", budget, || {
        let before = window_pixels(x, id);
        std::thread::sleep(Duration::from_millis(500));
        let pixels = window_pixels(x, id);
        let settled = changed(&before.2, &pixels.2) == 0;
        (settled && lit(&pixels.2) > pixels.2.len() / 6).then_some(pixels)
    })
}

/// The top-left `size` pixels of `pixels` (RGB rows), as an image of that size.
pub fn crop(pixels: &(u32, u32, Vec<u8>), [w, h]: [u32; 2]) -> Vec<u8> {
    let row = pixels.0 as usize * 3;
    (pixels.2.chunks_exact(row).take(h as usize))
        .flat_map(|r| &r[..w as usize * 3])
        .copied()
        .collect()
}
