//! `[room]` and `[mirror]`: the box and the sphere that every scene has.

use super::{position_at, sample_times, Ctx, R};
use crate::scene::format::{LookupSpec, MirrorSpec, RoomSpec, WallsSpec};
use crate::scene::{Lookup, Mirror, Room};

impl Ctx<'_> {
    pub(super) fn room(
        &self,
        spec: &RoomSpec,
        material: &dyn Fn(&str, &str) -> R<usize>,
    ) -> R<Room> {
        let center = match spec.center {
            Some(c) => self.point("room.center", c)?,
            // The world origin, which is not the local one.
            None => self.point("room.center", [0.0; 3])?,
        };
        let size_m = self.positive3("room.size", spec.size)?;
        let wall_materials = match &spec.walls {
            WallsSpec::All(name) => [material("room.walls", name)?; 6],
            WallsSpec::Each(w) => [
                material("room.walls.px", &w.px)?,
                material("room.walls.nx", &w.nx)?,
                material("room.walls.py", &w.py)?,
                material("room.walls.ny", &w.ny)?,
                material("room.walls.pz", &w.pz)?,
                material("room.walls.nz", &w.nz)?,
            ],
        };
        Ok(Room {
            center,
            size_m,
            wall_materials,
        })
    }

    pub(super) fn mirror(&self, spec: &MirrorSpec, room: &Room) -> R<Mirror> {
        let center = self.point("mirror.center", spec.center)?;
        let radius_m = self.positive("mirror.radius", spec.radius)?;
        let animation = match &spec.animation {
            Some(a) => Some(self.animation("mirror.animation", a, center)?),
            None => None,
        };
        let (lo, hi) = (
            room.center - room.size_m * 0.5,
            room.center + room.size_m * 0.5,
        );
        for t in sample_times(animation.as_ref()) {
            let c = position_at(animation.as_ref(), center, t);
            if (c - radius_m).cmplt(lo).any() || (c + radius_m).cmpgt(hi).any() {
                let field = if t == 0.0 {
                    "mirror.center"
                } else {
                    "mirror.animation"
                };
                return Err(self.invalid(
                    field,
                    format!(
                        "the mirror (radius {radius_m}) centred at {} {} is not entirely inside the room (from {} to {})",
                        self.fmt_point(c),
                        if t == 0.0 { "at time 0".to_string() } else { format!("at t = {t:.3} s") },
                        self.fmt_point(lo),
                        self.fmt_point(hi)
                    ),
                ));
            }
        }
        Ok(Mirror {
            center,
            radius_m,
            animation,
            lookup: match spec.lookup {
                None | Some(LookupSpec::Plain) => Lookup::Plain,
                Some(LookupSpec::Box) => Lookup::Box,
            },
        })
    }
}
