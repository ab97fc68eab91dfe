//! The derived barriers against the ones the frame placed by hand before the graph (and
//! against the rules: reads after reads need none, writes wait for every earlier access).

use super::*;
use crate::render::draw::NOTHING;

fn image(raw: u64, levels: u32) -> Resource {
    levels_of(raw, [0, levels], [0, 1])
}

/// Levels `mips` (first, count) of layers `layers` (first, count) of the colour image `raw`.
fn levels_of(raw: u64, [mip, mips]: [u32; 2], [layer, layers]: [u32; 2]) -> Resource {
    let range = vk::ImageSubresourceRange {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        base_mip_level: mip,
        level_count: mips,
        base_array_layer: layer,
        layer_count: layers,
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
    graph.import(colour, Use::CopySource, false);
    graph.import(depth, Use::DepthTarget, false);
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
    graph.import(colour, Use::CopySource, false);
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
    graph.import(cube, Use::FragmentRead, false);
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
    graph.import(cube, Use::FragmentRead, false);
    graph.import(depth, Use::DepthTarget, false);
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
    graph.import(buffer, Use::HostRead, false);
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

/// A cube of 6 faces and 3 levels after a fill, its chain blitted for faces 0 and 2 alone (as
/// `mips.rs` did before its compute pass): the barriers, each subresource's derived on its
/// own and merged back, are the ones once placed by hand (level 0 of all faces in one barrier,
/// each face's level alone, then back to sampling: all of level 0, levels 1.. of each face).
#[test]
fn the_mip_chain_of_two_dirty_faces_gets_the_hand_placed_barriers() {
    let cube = 5;
    let all = levels_of(cube, [0, 3], [0, 6]);
    let mut graph = FrameGraph::default();
    graph.import(all, Use::FragmentRead, false);
    let level0 = levels_of(cube, [0, 1], [0, 6]);
    let filled = graph.uses(&[(level0, Use::ColorKept)]);
    let sampled = (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, SAMPLED);
    let attachment = (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, COLOR_OUT);
    assert_eq!(filled, [image_barrier(level0, sampled, attachment)]);
    let src = (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, BLIT_READ);
    let dst = (vk::ImageLayout::TRANSFER_DST_OPTIMAL, BLIT_WRITE);
    let undefined_after_sampling = (vk::ImageLayout::UNDEFINED, SAMPLED);
    assert_eq!(
        graph.uses(&[(level0, Use::BlitSource)]),
        [image_barrier(level0, attachment, src)]
    );
    for m in 1..3 {
        let faces = [0, 2].map(|f| levels_of(cube, [m, 1], [f, 1]));
        let to_dst = graph.uses(&faces.map(|r| (r, Use::BlitDestination)));
        let expected = faces.map(|r| image_barrier(r, undefined_after_sampling, dst));
        assert_eq!(to_dst, expected, "level {m} into a blit destination");
        let to_src = graph.uses(&faces.map(|r| (r, Use::BlitSource)));
        assert_eq!(
            to_src,
            faces.map(|r| image_barrier(r, dst, src)),
            "level {m}"
        );
    }
    let back = graph.uses(&[(all, Use::FragmentRead)]);
    let expected = [
        image_barrier(level0, src, sampled),
        image_barrier(levels_of(cube, [1, 2], [0, 1]), src, sampled),
        image_barrier(levels_of(cube, [1, 2], [2, 1]), src, sampled),
    ];
    assert_eq!(
        back, expected,
        "clean faces' levels 1.. never left sampling"
    );
    assert_eq!(graph.finish(), []);
}

/// Before its first fill the cube's contents are undefined: the fill's barrier says so (and
/// still waits for the fragment shaders' reads, as a cube given up after a floor was sampled
/// by earlier frames), and a fresh image a frame leaves unused is left as it is.
#[test]
fn a_fresh_image_starts_undefined_and_is_left_alone_unused() {
    let (cube, ids) = (levels_of(6, [0, 1], [0, 6]), levels_of(7, [0, 1], [0, 6]));
    let mut graph = FrameGraph::default();
    graph.import(cube, Use::FragmentRead, true);
    graph.import(ids, Use::FragmentRead, true);
    assert_eq!(
        graph.uses(&[(cube, Use::ColorKept)]),
        [image_barrier(
            cube,
            (vk::ImageLayout::UNDEFINED, SAMPLED),
            (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, COLOR_OUT)
        )]
    );
    assert_eq!(
        graph.finish(),
        [image_barrier(
            cube,
            (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, COLOR_OUT),
            (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, SAMPLED)
        )],
        "the unused id cube is not touched"
    );
}

/// Merging covers exactly the subresources given: a gap in the layers or the levels splits
/// the range, and different sources are never merged.
#[test]
fn merged_ranges_cover_exactly_the_subresources_given() {
    let all = Subresources::of(vk::ImageSubresourceRange {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        base_mip_level: 0,
        level_count: 4,
        base_array_layer: 0,
        layer_count: 6,
    });
    let a = (vk::ImageLayout::UNDEFINED, NOTHING);
    let b = (vk::ImageLayout::GENERAL, SAMPLED);
    // Levels 0-1 of layers 0-1 and 3 from `a`; level 3 of layer 0 from `a` (a gap at level
    // 2); level 0 of layer 5 from `b`.
    let at = |m: usize, l: usize| m * 6 + l;
    let needed = vec![
        (at(0, 0), a),
        (at(0, 1), a),
        (at(0, 3), a),
        (at(1, 0), a),
        (at(1, 1), a),
        (at(1, 3), a),
        (at(3, 0), a),
        (at(0, 5), b),
    ];
    let merged = all.merge(needed);
    let range = |mips: [u32; 2], layers: [u32; 2]| {
        Subresources::of(vk::ImageSubresourceRange {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            base_mip_level: mips[0],
            level_count: mips[1],
            base_array_layer: layers[0],
            layer_count: layers[1],
        })
    };
    assert_eq!(
        merged,
        [
            (range([0, 2], [0, 2]), a),
            (range([0, 2], [3, 1]), a),
            (range([0, 1], [5, 1]), b),
            (range([3, 1], [0, 1]), a),
        ]
    );
}

/// A layout transition is made visible to the stages it was made for only: a copy after a
/// blit source, in the same layout, still needs a barrier (as does putting it back at rest),
/// where a second read at the same stage needs none.
#[test]
fn a_read_at_another_stage_waits_for_the_layout_transition() {
    let level = levels_of(8, [0, 1], [0, 1]);
    let mut graph = FrameGraph::default();
    graph.import(level, Use::FragmentRead, false);
    let src = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
    assert_eq!(graph.uses(&[(level, Use::BlitSource)]).len(), 1);
    assert_eq!(graph.uses(&[(level, Use::BlitSource)]), []);
    assert_eq!(
        graph.uses(&[(level, Use::CopySource)]),
        [image_barrier(level, (src, BLIT_READ), (src, COPY_READ))]
    );
    assert_eq!(graph.uses(&[(level, Use::CopySource)]), []);
    assert_eq!(graph.finish().len(), 1, "back to sampling");
}

fn buffer(raw: u64) -> Resource {
    Resource::Buffer(vk::Handle::from_raw(raw))
}

/// An upload's destination: the copy waits for every earlier command's reads of it (the
/// frames still in flight), and the copy's writes are made visible to any later read, as
/// `vk::uploads` placed them by hand (with `MEMORY_READ` named on the source side, where the
/// hand-placed barrier named no access: an execution dependency either way).
#[test]
fn an_upload_waits_for_earlier_reads_and_is_read_anywhere_after() {
    let (views, objects) = (buffer(1), buffer(2));
    let mut graph = FrameGraph::default();
    graph.import(views, Use::ReadAnywhere, false);
    graph.import(objects, Use::ReadAnywhere, false);
    let copy = graph.uses(&[
        (views, Use::CopyDestination),
        (objects, Use::CopyDestination),
    ]);
    assert_eq!(copy, [Barrier::Memory(ANY_READ, COPY_WRITE); 2]);
    let read = graph.uses(&[(views, Use::ReadAnywhere), (objects, Use::ReadAnywhere)]);
    assert_eq!(read, [Barrier::Memory(COPY_WRITE, ANY_READ); 2]);
    assert_eq!(graph.finish(), [], "both rest as read anywhere");
}

/// The top level's rebuild: after the last frame's ray queries read the structure and its
/// build wrote the scratch, and visible to this frame's ray queries after, as
/// `vk::acceleration` placed it by hand.
#[test]
fn a_top_level_rebuild_waits_for_the_last_traces_and_precedes_the_next() {
    let (structure, scratch) = (buffer(1), buffer(2));
    let mut graph = FrameGraph::default();
    graph.import(structure, Use::AccelerationTraced, false);
    graph.import(scratch, Use::AccelerationBuild, false);
    let build = graph.uses(&[
        (structure, Use::AccelerationBuild),
        (scratch, Use::AccelerationBuild),
    ]);
    assert_eq!(
        build,
        [
            Barrier::Memory(TRACED, BUILD_RW),
            Barrier::Memory(BUILD_RW, BUILD_RW)
        ]
    );
    let traced = graph.uses(&[(structure, Use::AccelerationTraced)]);
    assert_eq!(traced, [Barrier::Memory(BUILD_RW, TRACED)]);
    assert_eq!(graph.finish(), []);
}

/// The traced rays' tally: zeroed after the last frame's copy read it, counted into by the
/// fragment shaders, copied for the host; the host copy needs no barrier before the copy
/// (only the host used it, before the submission) and one for the host after.
#[test]
fn a_tally_is_zeroed_counted_and_copied_for_the_host() {
    let (tally, host) = (buffer(1), buffer(2));
    let mut graph = FrameGraph::default();
    graph.import(tally, Use::CopySource, false);
    graph.import(host, Use::HostRead, false);
    assert_eq!(
        graph.uses(&[(tally, Use::Filled)]),
        [Barrier::Memory(COPY_READ, FILL_WRITE)]
    );
    assert_eq!(
        graph.uses(&[(tally, Use::FragmentStorage)]),
        [Barrier::Memory(FILL_WRITE, STORAGE_RW)]
    );
    let copy = graph.uses(&[(tally, Use::CopySource), (host, Use::CopyDestination)]);
    assert_eq!(copy, [Barrier::Memory(STORAGE_RW, COPY_READ)]);
    let host_read = (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ);
    assert_eq!(
        graph.uses(&[(host, Use::HostRead)]),
        [Barrier::Memory(COPY_WRITE, host_read)]
    );
    assert_eq!(graph.finish(), []);
}

/// A host read declared within the frame is the host's use after the fence: a device write
/// after it in the same frame still waits for the device's writes before it (only the host's
/// use before the submission, as the buffer was imported, needs no barrier).
#[test]
fn a_host_read_within_the_frame_does_not_excuse_a_later_write() {
    let host = buffer(1);
    let host_read = (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ);
    let mut graph = FrameGraph::default();
    graph.import(host, Use::HostRead, false);
    assert_eq!(graph.uses(&[(host, Use::CopyDestination)]), []);
    assert_eq!(
        graph.uses(&[(host, Use::HostRead)]),
        [Barrier::Memory(COPY_WRITE, host_read)]
    );
    assert_eq!(
        graph.uses(&[(host, Use::CopyDestination)]),
        [Barrier::Memory(host_read, COPY_WRITE)]
    );
}
