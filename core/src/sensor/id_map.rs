//! What the sensor's id layer names, and the classes beside it: the room's six walls (ids 0..6,
//! in the cube faces' order) and the scene's objects (6 + their index), each with its name,
//! material, shape and class. Ids and classes are the scene's, the same in every frame
//! (`sensor.id.json`; docs/sensor.md, "Ids and classes").

use serde::Serialize;

use crate::scene::Scene;

/// The id (and class) of a pixel that sees no object through the mirror (or not the mirror at
/// all).
pub const NO_ID: u32 = u32::MAX;

/// Every drawable the id layer can name, and the classes the class layer can.
#[derive(Debug, Clone, Serialize)]
pub struct IdMap {
    /// The id (and class) of a pixel that sees no drawable (or not the mirror).
    pub no_id: u32,
    pub drawables: Vec<Drawable>,
    /// The class names by class id: the walls' classes first (`wall`, `ceiling`, `floor`),
    /// then the objects' in the order they first appear in the scene.
    pub classes: Vec<String>,
}

#[derive(Debug, Clone, Serialize)]
pub struct Drawable {
    pub id: u32,
    /// "wall" or "object".
    pub kind: &'static str,
    pub name: String,
    pub material: String,
    /// `wall`, `box`, `sphere`, `cylinder` or `mesh FILE`.
    pub shape: String,
    /// What it is (`wall`, `ceiling`, `floor`; an object's from its scene file, else
    /// `object`), and that class's index in [`IdMap::classes`].
    pub class: String,
    pub class_id: u32,
}

/// The walls' names and classes, in the cube faces' order.
const WALLS: [(&str, &str); 6] = [
    ("+X wall", "wall"),
    ("-X wall", "wall"),
    ("ceiling (+Y)", "ceiling"),
    ("floor (-Y)", "floor"),
    ("+Z wall", "wall"),
    ("-Z wall", "wall"),
];

impl IdMap {
    pub fn of(scene: &Scene) -> Self {
        let material = |m: usize| scene.materials[m].name.clone();
        let walls = (WALLS.iter().zip(scene.room.wall_materials)).map(|(&(name, class), m)| {
            let about = (name.to_owned(), material(m), "wall".to_owned());
            ("wall", about, class.to_owned())
        });
        let objects = (scene.objects.iter()).map(|o| {
            let about = (o.name.clone(), material(o.material), o.shape.clone());
            ("object", about, o.class.clone())
        });
        let mut classes: Vec<String> = Vec::new();
        let drawables = (walls.chain(objects).enumerate())
            .map(|(id, (kind, (name, material, shape), class))| {
                let class_id = match classes.iter().position(|c| *c == class) {
                    Some(at) => at,
                    None => {
                        classes.push(class.clone());
                        classes.len() - 1
                    }
                };
                Drawable {
                    id: id as u32,
                    kind,
                    name,
                    material,
                    shape,
                    class,
                    class_id: class_id as u32,
                }
            })
            .collect();
        Self {
            no_id: NO_ID,
            drawables,
            classes,
        }
    }

    /// The class of each id in `ids` ([`NO_ID`] stays [`NO_ID`]).
    pub fn classes_of(&self, ids: &[u32]) -> Vec<u32> {
        let class = |&id: &u32| match self.drawables.get(id as usize) {
            Some(d) => d.class_id,
            None => NO_ID,
        };
        ids.iter().map(class).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A room with classed objects, a generated crowd and an unclassed one: the walls' classes
    /// first, then each object's class once, in the order they appear; every pixel's class is
    /// its id's.
    #[test]
    fn classes_are_numbered_once_in_order_and_follow_the_ids() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let text = std::fs::read_to_string(root.join("scenes/test/six-colour-room.toml"))
            .expect("the six-colour room")
            + r#"
[[objects]]
name = "seat"
class = "chair"
shape = "box"
size = [0.4, 0.4, 0.4]
position = [1.5, -1.0, 1.5]
material = "red"

[[objects]]
shape = "sphere"
radius = 0.2
position = [-1.5, -1.0, 1.5]
material = "red"

[[generate]]
class = "chair"
count = 3
shapes = ["box"]
size = [0.2, 0.3]
region_min = [-2.0, -1.2, -2.0]
region_max = [2.0, -0.8, -1.5]
materials = ["red"]
"#;
        // Read from memory, as the room's own file would be: nothing is written.
        let path = root.join("scenes/test/classes.toml");
        let scene = crate::scene::load_str(&text, &path).expect("the scene with classes");
        let map = IdMap::of(&scene);
        assert_eq!(map.classes, ["wall", "ceiling", "floor", "chair", "object"]);
        let of = |id: usize| (map.drawables[id].class.as_str(), map.drawables[id].class_id);
        assert_eq!(
            [of(0), of(2), of(3), of(5)],
            [("wall", 0), ("ceiling", 1), ("floor", 2), ("wall", 0)]
        );
        assert_eq!([of(6), of(7)], [("chair", 3), ("object", 4)]);
        assert_eq!(map.drawables.len(), 6 + 2 + 3);
        assert!((8..11).all(|id| of(id) == ("chair", 3)));
        let ids = [0, 7, NO_ID, 9, 3];
        assert_eq!(map.classes_of(&ids), [0, 4, NO_ID, 3, 2]);
    }
}
