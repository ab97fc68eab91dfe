//! Where each point's label goes, in pixels: beside its point when there is room there, else
//! further out with a leader line back to the point, else nowhere in the plotting area (the
//! caller lists it outside). A placed label never overlaps another label, a point's marker,
//! a reserved box or a leader line, and never leaves the bounds; a leader never crosses a
//! label, a reserved box or a marker other than its own point's cluster.
//!
//! The search tries the eight spots beside the point that cartographers use, then walks rings
//! of growing radius around it, a few angles per ring (level with the point first: text is
//! wide, and a label level with its point reads as its own), moving each ring's box into the
//! bounds when it sticks out, and takes the first free one. Labels are placed in the order
//! given, so the caller puts the ones that matter most first; when some are left without
//! room, those are placed first and all again. The text keeps to the side of its box that
//! faces its point, since the box's width is only an estimate of the text's.

/// The markers' radius (the plot draws its circles with it).
pub const MARKER_RADIUS_PX: i32 = 5;
/// How near a label may come to a marker's centre: the radius, the hollow marker's stroke and
/// a pixel of air.
const MARKER_CLEARANCE_PX: f64 = 7.5;
/// The spots beside a point: the label's nearest edge this far from its centre (3 px of air
/// beside the marker); the rings start one step further out.
const FIRST_RING_PX: f64 = 8.0;
/// How much each ring grows, and the spacing of the angles along a ring: about half a line
/// of text, fine enough to find a gap between two labels.
const RING_STEP_PX: f64 = 8.0;
const ARC_STEP_PX: f64 = 10.0;
/// A label whose box is further than this from its marker's edge gets a leader line (a label
/// nearer than this is read as its point's without one).
const LEADER_GAP_PX: f64 = 10.0;
/// How many times the labels left without room are moved to the front and all placed again.
const RETRIES: usize = 3;
/// Air around the text inside its box.
const TEXT_PAD_PX: i32 = 2;

/// A box in pixels: left, top, right, bottom (right and bottom are the edges, so two boxes
/// that only touch do not overlap).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect(pub i32, pub i32, pub i32, pub i32);

impl Rect {
    pub fn overlaps(&self, o: &Rect) -> bool {
        self.0 < o.2 && o.0 < self.2 && self.1 < o.3 && o.1 < self.3
    }
    pub fn inside(&self, o: &Rect) -> bool {
        self.0 >= o.0 && self.1 >= o.1 && self.2 <= o.2 && self.3 <= o.3
    }
    /// Where a label's text is drawn: the top of its padded edge nearest `point` (the middle
    /// when the point is about above or below the middle), and which way the text runs from
    /// there, so that the text meets its point whatever the viewer's font makes of the
    /// estimated width.
    pub fn text_anchor(&self, point: (i32, i32)) -> ((i32, i32), Align) {
        let (top, middle) = (self.1 + TEXT_PAD_PX, (self.0 + self.2) / 2);
        let off = point.0 - middle;
        if off.abs() <= (self.2 - self.0) / 6 {
            ((middle, top), Align::Centre)
        } else if off < 0 {
            ((self.0 + TEXT_PAD_PX, top), Align::Left)
        } else {
            ((self.2 - TEXT_PAD_PX, top), Align::Right)
        }
    }
    /// The box shifted the least that puts it inside `o` (unmoved if it cannot fit).
    fn moved_into(self, o: &Rect) -> Rect {
        let shift = |lo: i32, hi: i32, olo: i32, ohi: i32| {
            if hi - lo > ohi - olo {
                0
            } else {
                (olo - lo).max(0) + (ohi - hi).min(0)
            }
        };
        let dx = shift(self.0, self.2, o.0, o.2);
        let dy = shift(self.1, self.3, o.1, o.3);
        Rect(self.0 + dx, self.1 + dy, self.2 + dx, self.3 + dy)
    }
    /// The point of the box nearest to `p` (`p` itself when inside).
    fn nearest(&self, p: (f64, f64)) -> (f64, f64) {
        (
            p.0.clamp(f64::from(self.0), f64::from(self.2)),
            p.1.clamp(f64::from(self.1), f64::from(self.3)),
        )
    }
    /// How far the box is from the point `c`.
    fn distance(&self, c: (i32, i32)) -> f64 {
        let c = as_f64(c);
        let n = self.nearest(c);
        (n.0 - c.0).hypot(n.1 - c.1)
    }
    /// Whether a marker centred at `c` comes nearer than the clearance.
    fn crowds(&self, c: (i32, i32)) -> bool {
        self.distance(c) < MARKER_CLEARANCE_PX
    }
}

/// The box a text of `chars` characters takes at `font_px` (the size drawn). The width is an
/// estimate, 0.6 em a character: wide enough for the common sans-serif fonts (DejaVu Sans,
/// which rsvg picks, averages 0.52 em on these labels; Arial less), since the SVG names no
/// font and the viewer picks one.
pub fn text_box(chars: usize, font_px: f64) -> (i32, i32) {
    let w = (chars as f64 * 0.6 * font_px).ceil() as i32;
    let h = (1.05 * font_px).ceil() as i32;
    (w + 2 * TEXT_PAD_PX, h + 2 * TEXT_PAD_PX)
}

/// Which end of a label's text its anchor is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Align {
    Left,
    Centre,
    Right,
}

/// A label to place: its point and its box's size.
#[derive(Clone, Copy, Debug)]
pub struct Label {
    pub at: (i32, i32),
    pub size: (i32, i32),
}

/// Where a label went.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spot {
    /// Next to its point.
    Beside(Rect),
    /// Further out, with a leader line from the marker's edge to the box (both ends given).
    Leader(Rect, (i32, i32), (i32, i32)),
    /// No free box in the bounds: to be listed outside the plotting area.
    Listed,
}

impl Spot {
    pub fn rect(&self) -> Option<Rect> {
        match *self {
            Spot::Beside(r) | Spot::Leader(r, ..) => Some(r),
            Spot::Listed => None,
        }
    }
}

/// Every label's spot, by the label's index. The markers are the labels' points.
pub fn place(labels: &[Label], bounds: Rect, reserved: &[Rect]) -> Vec<Spot> {
    let listed = |spots: &[Spot]| spots.iter().filter(|s| **s == Spot::Listed).count();
    let mut order: Vec<usize> = (0..labels.len()).collect();
    let mut best = place_in_order(labels, &order, bounds, reserved);
    let mut last = best.clone();
    // A label left without room is where the crowd is: placed first, it may take a spot that
    // an earlier one did not need. Kept only if fewer are left over.
    for _ in 0..RETRIES {
        if listed(&last) == 0 {
            break;
        }
        order.sort_by_key(|&i| last[i] != Spot::Listed);
        last = place_in_order(labels, &order, bounds, reserved);
        if listed(&last) < listed(&best) {
            best = last.clone();
        }
    }
    best
}

/// The spots when the labels are placed in this order (the spots by the label's index).
fn place_in_order(labels: &[Label], order: &[usize], bounds: Rect, reserved: &[Rect]) -> Vec<Spot> {
    let markers: Vec<(i32, i32)> = labels.iter().map(|l| l.at).collect();
    let mut taken = Taken {
        boxes: reserved.to_vec(),
        leaders: Vec::new(),
    };
    let mut spots = vec![Spot::Listed; labels.len()];
    for &i in order {
        let label = &labels[i];
        let spot = candidates(label, bounds)
            .map(|r| with_leader(r, label.at))
            .find(|s| taken.allows(s, label.at, &markers, bounds))
            .unwrap_or(Spot::Listed);
        taken.add(&spot);
        spots[i] = spot;
    }
    spots
}

/// Whether a label beside its point is nearer to it than to any other point (but those of its
/// own cluster, which are as near): without a leader, nearness is what says whose it is.
fn owned(r: &Rect, at: (i32, i32), markers: &[(i32, i32)]) -> bool {
    let own = r.distance(at);
    markers
        .iter()
        .filter(|&&m| !same_cluster(m, at))
        .all(|&m| r.distance(m) > own)
}

/// Whether two markers overlap (or nearly): their labels cannot tell them apart by nearness,
/// and a leader from one starts over the other.
fn same_cluster(m: (i32, i32), at: (i32, i32)) -> bool {
    (m.0 - at.0).abs().max((m.1 - at.1).abs()) <= 2 * MARKER_RADIUS_PX + 2
}

/// What earlier labels (and the reserved boxes) occupy.
struct Taken {
    boxes: Vec<Rect>,
    leaders: Vec<((f64, f64), (f64, f64))>,
}

impl Taken {
    fn allows(&self, spot: &Spot, at: (i32, i32), markers: &[(i32, i32)], bounds: Rect) -> bool {
        let Some(r) = spot.rect() else {
            return false;
        };
        let box_free = r.inside(&bounds)
            && !self.boxes.iter().any(|b| b.overlaps(&r))
            && !markers.iter().any(|&m| r.crowds(m))
            && !self.leaders.iter().any(|&(a, b)| segment_hits(a, b, &r));
        box_free
            && match *spot {
                Spot::Leader(_, a, b) => self.leader_free(a, b, at, markers),
                Spot::Beside(_) => owned(&r, at, markers),
                Spot::Listed => false,
            }
    }

    /// A leader crosses no label and passes no marker closely but those of its own cluster
    /// (it starts among them).
    fn leader_free(
        &self,
        a: (i32, i32),
        b: (i32, i32),
        at: (i32, i32),
        markers: &[(i32, i32)],
    ) -> bool {
        let (a, b) = (as_f64(a), as_f64(b));
        // Clear of a marker by more than a stroke, so that it is not read as that marker's.
        let r = MARKER_RADIUS_PX + 4;
        !self.boxes.iter().any(|x| segment_hits(a, b, x))
            && !markers
                .iter()
                .filter(|&&m| !same_cluster(m, at))
                .any(|&(x, y)| segment_hits(a, b, &Rect(x - r, y - r, x + r, y + r)))
    }

    fn add(&mut self, spot: &Spot) {
        if let Some(r) = spot.rect() {
            self.boxes.push(r);
        }
        if let Spot::Leader(_, a, b) = *spot {
            self.leaders.push((as_f64(a), as_f64(b)));
        }
    }
}

fn as_f64(p: (i32, i32)) -> (f64, f64) {
    (f64::from(p.0), f64::from(p.1))
}

/// The candidate boxes around a label's point: the spots beside it, then rings of growing
/// radius until one lies wholly beyond the bounds, each ring's boxes moved into the bounds
/// where they stick out (a spot beside the point is taken as it is or not at all: moved, it
/// could sit over a neighbour).
fn candidates(label: &Label, bounds: Rect) -> impl Iterator<Item = Rect> + '_ {
    let diagonal = f64::from(bounds.2 - bounds.0).hypot(f64::from(bounds.3 - bounds.1));
    let rings = (diagonal / RING_STEP_PX).ceil() as usize + 1;
    let around = (1..rings).flat_map(move |k| {
        let radius = FIRST_RING_PX + k as f64 * RING_STEP_PX;
        ring_angles(radius)
            .into_iter()
            .map(move |angle| box_at(label, radius, angle).moved_into(&bounds))
    });
    beside(label).into_iter().chain(around)
}

/// The eight spots beside a point, as cartographers rank them: level with it right and left,
/// stacked above and below those (a pixel apart, so that a cluster of points gets a column of
/// labels on each side), then centred above and below.
fn beside(label: &Label) -> [Rect; 8] {
    let ((x, y), (w, h)) = (label.at, label.size);
    let gap = FIRST_RING_PX as i32;
    let (right, left, centred) = (x + gap, x - gap - w, x - w / 2);
    let level = y - h / 2;
    let (upper, lower) = (level - h - 1, level + h + 1);
    [
        (right, level),
        (left, level),
        (right, upper),
        (right, lower),
        (left, upper),
        (left, lower),
        (centred, y - gap - h),
        (centred, y + gap),
    ]
    .map(|(l, t)| Rect(l, t, l + w, t + h))
}

/// A ring's angles (radians, y down), in order of preference: level with the point first,
/// right before left, above before below.
fn ring_angles(radius: f64) -> Vec<f64> {
    // A multiple of 8, so that the four sides and the diagonals are always among them.
    let n = ((std::f64::consts::TAU * radius / ARC_STEP_PX / 8.0).ceil() as usize).max(1) * 8;
    let mut angles: Vec<f64> = (0..n)
        .map(|i| i as f64 * std::f64::consts::TAU / n as f64)
        .collect();
    let rank = |a: f64| {
        let (s, c) = a.sin_cos();
        // Level first, then right of left; among equals, the upper one.
        (s.abs() * 2.0 + if c < -1e-9 { 1.0 } else { 0.0 }, s)
    };
    angles.sort_by(|a, b| rank(*a).partial_cmp(&rank(*b)).expect("finite angles"));
    angles
}

/// The label's box whose edge (or corner) nearest the point lies `radius` from it at `angle`:
/// to the right of the point the box starts there, to the left it ends there, straight above
/// or below it is centred.
fn box_at(label: &Label, radius: f64, angle: f64) -> Rect {
    let (w, h) = (f64::from(label.size.0), f64::from(label.size.1));
    let (s, c) = angle.sin_cos();
    let x = f64::from(label.at.0) + radius * c;
    let y = f64::from(label.at.1) + radius * s;
    // cos 67.5°: beyond it the box sits beside the point rather than over it.
    const SIDE: f64 = 0.38;
    let left = match c {
        c if c > SIDE => x,
        c if c < -SIDE => x - w,
        _ => x - w / 2.0,
    };
    let top = match s {
        s if s > SIDE => y,
        s if s < -SIDE => y - h,
        _ => y - h / 2.0,
    };
    let (l, t) = (left.round() as i32, top.round() as i32);
    Rect(l, t, l + label.size.0, t + label.size.1)
}

/// The spot for a box: beside the point when near it, else with a leader from the marker's
/// edge to the box's nearest point.
fn with_leader(r: Rect, at: (i32, i32)) -> Spot {
    let c = as_f64(at);
    let end = r.nearest(c);
    let d = (end.0 - c.0).hypot(end.1 - c.1);
    let radius = f64::from(MARKER_RADIUS_PX);
    if d <= radius + LEADER_GAP_PX {
        return Spot::Beside(r);
    }
    let start = (
        c.0 + (end.0 - c.0) * radius / d,
        c.1 + (end.1 - c.1) * radius / d,
    );
    let px = |p: (f64, f64)| (p.0.round() as i32, p.1.round() as i32);
    Spot::Leader(r, px(start), px(end))
}

/// Whether the segment from `a` to `b` meets the box (edges included): Liang and Barsky's
/// clipping, the segment as `a + t (b - a)` for t in [0, 1].
fn segment_hits(a: (f64, f64), b: (f64, f64), r: &Rect) -> bool {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (l, t, rt, bt) = (
        f64::from(r.0),
        f64::from(r.1),
        f64::from(r.2),
        f64::from(r.3),
    );
    let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
    for (p, q) in [
        (-dx, a.0 - l),
        (dx, rt - a.0),
        (-dy, a.1 - t),
        (dy, bt - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return false;
            }
        } else if p < 0.0 {
            t0 = t0.max(q / p);
        } else {
            t1 = t1.min(q / p);
        }
    }
    t0 <= t1
}

#[cfg(test)]
mod tests {
    use super::*;
    use specchio::random::SplitMix64;

    fn label(at: (i32, i32), chars: usize) -> Label {
        Label {
            at,
            size: text_box(chars, 12.9),
        }
    }

    #[test]
    fn labels_avoid_each_other_and_the_edges() {
        let bounds = Rect(0, 0, 400, 300);
        let spots = place(&[label((100, 100), 7), label((100, 100), 9)], bounds, &[]);
        let (first, second) = (spots[0].rect().unwrap(), spots[1].rect().unwrap());
        // Right of the point first, level with it; a second point at the same spot takes
        // another place.
        assert_eq!(spots[0], Spot::Beside(first));
        assert!(first.0 > 100 && first.1 < 100 && first.3 > 100, "{first:?}");
        assert!(!second.overlaps(&first), "{first:?} {second:?}");
        // Near the right edge the label goes to the left of the point.
        let left = place(&[label((395, 100), 14)], bounds, &[])[0]
            .rect()
            .unwrap();
        assert!(left.2 < 395 && left.inside(&bounds), "{left:?}");
    }

    #[test]
    fn a_crowded_point_gets_a_leader_and_a_full_panel_a_list() {
        // Eight labels on one point: the ring beside it holds a few, the rest go further out
        // with leaders that start on the marker's edge.
        let spots = place(&[label((200, 150), 14); 8], Rect(0, 0, 400, 300), &[]);
        let leaders: Vec<_> = spots
            .iter()
            .filter_map(|s| match *s {
                Spot::Leader(_, a, _) => Some(a),
                _ => None,
            })
            .collect();
        assert!(
            !leaders.is_empty() && !spots.contains(&Spot::Listed),
            "{spots:?}"
        );
        for (x, y) in leaders {
            let d = f64::from(x - 200).hypot(f64::from(y - 150));
            assert!(
                (d - 5.0).abs() <= 1.0,
                "leader starts {d} px from the centre"
            );
        }
        // Bounds that fit one label: the second is listed, not drawn over the first.
        let spots = place(
            &[label((20, 15), 5), label((20, 15), 5)],
            Rect(0, 0, 90, 30),
            &[],
        );
        assert!(
            spots[0].rect().is_some() && spots[1] == Spot::Listed,
            "{spots:?}"
        );
    }

    #[test]
    fn text_keeps_to_the_side_facing_its_point() {
        let r = Rect(100, 50, 220, 68);
        assert_eq!(r.text_anchor((92, 59)), ((102, 52), Align::Left));
        assert_eq!(r.text_anchor((228, 59)), ((218, 52), Align::Right));
        assert_eq!(r.text_anchor((165, 80)), ((160, 52), Align::Centre));
        // Over the box's left part (a box moved into the bounds): from its left edge.
        assert_eq!(r.text_anchor((110, 80)), ((102, 52), Align::Left));
    }

    #[test]
    fn segments_meet_boxes_they_cross_and_miss_the_others() {
        let r = Rect(10, 10, 20, 20);
        assert!(segment_hits((0.0, 15.0), (30.0, 15.0), &r)); // straight through
        assert!(segment_hits((15.0, 15.0), (15.0, 40.0), &r)); // from inside
        assert!(!segment_hits((0.0, 0.0), (30.0, 5.0), &r)); // above it
        assert!(!segment_hits((0.0, 25.0), (25.0, 50.0), &r)); // below a corner
        assert!(segment_hits((0.0, 0.0), (30.0, 30.0), &r)); // the diagonal
    }

    /// Deterministic noise on the project's one seeded sequence, so that a failure replays.
    struct Noise(SplitMix64);

    impl Noise {
        /// Uniform in `lo..=hi` (lo <= hi).
        fn int(&mut self, lo: i32, hi: i32) -> i32 {
            lo + self.0.below((hi - lo + 1) as usize) as i32
        }
    }

    /// A plot's points: clusters of nearly coincident ones (the distance rungs), and a few
    /// strays, anywhere in the bounds (edges included: a FLIP of 0 sits on the floor) but
    /// under the legend.
    fn layout(noise: &mut Noise, bounds: Rect, legend: Rect) -> Vec<Label> {
        let somewhere = |noise: &mut Noise| loop {
            let at = (noise.int(bounds.0, bounds.2), noise.int(bounds.1, bounds.3));
            if !Rect(at.0 - 8, at.1 - 8, at.0 + 8, at.1 + 8).overlaps(&legend) {
                return at;
            }
        };
        let mut labels = Vec::new();
        for _ in 0..noise.int(1, 4) {
            let (cx, cy) = somewhere(noise);
            for _ in 0..noise.int(1, 5) {
                let at = (cx + noise.int(-3, 3), cy + noise.int(-3, 3));
                labels.push(label(at, noise.int(5, 20) as usize));
            }
        }
        for _ in 0..noise.int(0, 6) {
            let at = somewhere(noise);
            labels.push(label(at, noise.int(5, 20) as usize));
        }
        labels
    }

    #[test]
    fn no_label_overlaps_anything_in_many_random_layouts() {
        let mut noise = Noise(SplitMix64::new(0x5eed_1ab1e5));
        let mut listed = 0;
        let mut total = 0;
        for case in 0..300 {
            let bounds = Rect(70, 40, 70 + noise.int(200, 520), 40 + noise.int(120, 320));
            let legend = Rect(bounds.2 - 150, bounds.1, bounds.2, bounds.1 + 50);
            let labels = layout(&mut noise, bounds, legend);
            let spots = place(&labels, bounds, &[legend]);
            let boxes: Vec<Rect> = spots.iter().filter_map(Spot::rect).collect();
            for (i, r) in boxes.iter().enumerate() {
                assert!(r.inside(&bounds), "case {case}: {r:?} leaves {bounds:?}");
                assert!(!r.overlaps(&legend), "case {case}: {r:?} on the legend");
                for o in &boxes[i + 1..] {
                    assert!(!r.overlaps(o), "case {case}: {r:?} on {o:?}");
                }
                for l in &labels {
                    assert!(
                        !r.crowds(l.at),
                        "case {case}: {r:?} on the marker {:?}",
                        l.at
                    );
                }
                for s in &spots {
                    if let Spot::Leader(own, a, b) = *s {
                        let crosses = own != *r && segment_hits(as_f64(a), as_f64(b), r);
                        assert!(!crosses, "case {case}: a leader crosses {r:?}");
                    }
                }
            }
            // Where the labels would cover less than a fifth of the free room, as on our
            // panels, the search finds room for nearly every one: listing is the last resort
            // (left for points walled in by their neighbours' labels at an edge).
            let covered: i32 = labels.iter().map(|l| l.size.0 * l.size.1).sum();
            let room = (bounds.2 - bounds.0) * (bounds.3 - bounds.1) - 150 * 50;
            if covered * 5 < room {
                listed += spots.iter().filter(|s| **s == Spot::Listed).count();
                total += spots.len();
            }
        }
        assert!(total > 500, "only {total} labels in sparse layouts");
        assert!(listed * 50 <= total, "{listed} of {total} labels listed");
    }
}
