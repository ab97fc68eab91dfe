//! The derived barriers against the ones the frame placed by hand before the graph (and
//! against the rules: reads after reads need none, writes wait for every earlier access).

use super::*;

fn image(raw: u64, levels: u32) -> Resource {
    let range = vk::ImageSubresourceRange {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        base_mip_level: 0,
        level_count: levels,
        base_array_layer: 0,
        layer_count: 1,
    };
    Resource::image(vk::Handle::from_raw(raw), range)
}

fn image_barrier(
    resource: Resource,
    from: (vk::ImageLayout, Sync),
    to: (vk::ImageLayout, Sync),
) -> Barrier {
    let Resource::Image(image, range) = resource else {
        panic!("an image")
    };
    Barrier::Image {
        image,
        range,
        from,
        to,
    }
}

/// A view target's frame: drawn (colour and depth cleared), then copied for the readback,
/// and left as the next frame finds it. The barriers are the ones `passes.rs` placed by hand.
#[test]
fn a_view_drawn_then_copied_gets_the_hand_placed_barriers() {
    let (colour, depth) = (image(1, 1), image(2, 1));
    let mut graph = FrameGraph::default();
    graph.import(colour, Use::CopySource);
    graph.import(depth, Use::DepthTarget);
    let drawn = graph.uses(&[(colour, Use::ColorTarget), (depth, Use::DepthTarget)]);
    assert_eq!(
        drawn,
        [
            image_barrier(
                colour,
                (vk::ImageLayout::UNDEFINED, COPY_READ),
                (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, COLOR_OUT)
            ),
            image_barrier(
                depth,
                (vk::ImageLayout::UNDEFINED, DEPTH_RW),
                (vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, DEPTH_RW)
            ),
        ]
    );
    let copied = graph.uses(&[(colour, Use::CopySource)]);
    assert_eq!(
        copied,
        [image_barrier(
            colour,
            (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, COLOR_OUT),
            (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, COPY_READ)
        )]
    );
    assert_eq!(graph.finish(), [], "both are at rest already");
}

/// A view drawn and not copied is still put back at rest: the next frame's barrier assumes it.
#[test]
fn a_view_left_as_an_attachment_is_put_back_at_rest() {
    let colour = image(1, 1);
    let mut graph = FrameGraph::default();
    graph.import(colour, Use::CopySource);
    graph.uses(&[(colour, Use::ColorTarget)]);
    assert_eq!(
        graph.finish(),
        [image_barrier(
            colour,
            (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, COLOR_OUT),
            (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, COPY_READ)
        )]
    );
}

/// The cube's mip 0, sampled between frames, copied for the readback and given back to the
/// fragment shaders: `readback.rs`'s two hand-placed barriers.
#[test]
fn the_cube_copied_goes_back_to_sampling() {
    let cube = image(3, 1);
    let mut graph = FrameGraph::default();
    graph.import(cube, Use::FragmentRead);
    assert_eq!(
        graph.uses(&[(cube, Use::CopySource)]),
        [image_barrier(
            cube,
            (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, SAMPLED),
            (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, COPY_READ)
        )]
    );
    assert_eq!(
        graph.finish(),
        [image_barrier(
            cube,
            (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, COPY_READ),
            (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, SAMPLED)
        )]
    );
    assert_eq!(graph.finish(), [], "once at rest, nothing more");
}

#[test]
fn reads_after_reads_need_no_barrier_and_writes_wait_for_writes() {
    let (cube, depth) = (image(3, 1), image(2, 1));
    let mut graph = FrameGraph::default();
    graph.import(cube, Use::FragmentRead);
    graph.import(depth, Use::DepthTarget);
    assert_eq!(graph.uses(&[(cube, Use::FragmentRead)]), []);
    assert_eq!(graph.uses(&[(cube, Use::FragmentRead)]), []);
    graph.uses(&[(depth, Use::DepthTarget)]);
    assert_eq!(
        graph.uses(&[(depth, Use::DepthTarget)]),
        [image_barrier(
            depth,
            (vk::ImageLayout::UNDEFINED, DEPTH_RW),
            (vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, DEPTH_RW)
        )],
        "a write after a write waits for it"
    );
}

/// The readback buffer: the host read it before this submission (no barrier before the
/// copies), and the copies' writes are made visible to the host at the end.
#[test]
fn the_readback_buffer_needs_only_the_host_barrier() {
    let buffer = Resource::Buffer(vk::Handle::from_raw(4));
    let mut graph = FrameGraph::default();
    graph.import(buffer, Use::HostRead);
    assert_eq!(graph.uses(&[(buffer, Use::CopyDestination)]), []);
    assert_eq!(graph.uses(&[(buffer, Use::CopyDestination)]).len(), 1);
    assert_eq!(
        graph.finish(),
        [Barrier::Memory(COPY_WRITE, Use::HostRead.sync())]
    );
}

#[test]
#[should_panic(expected = "a declared resource is imported")]
fn a_resource_never_imported_is_refused() {
    FrameGraph::default().uses(&[(image(9, 1), Use::CopySource)]);
}
