//! What a computation read, by content: the digests of every file read through
//! [`super::read_regular_file`] while a closure runs on this thread. A resumable dataset
//! (sensor/dataset/resume.rs) keeps them, so that a run resumed after its scene, a mesh, a
//! texture or its trajectory changed is refused instead of mixing frames of two rooms.

use std::cell::RefCell;

/// One file's content, by length and CRC-32: enough to tell an edited input from the same
/// one (it is no defence against a crafted collision, which nobody resuming their own run
/// has reason to make).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Digest {
    pub bytes: u64,
    pub crc32: u32,
}

impl Digest {
    pub fn of(bytes: &[u8]) -> Digest {
        Digest {
            bytes: bytes.len() as u64,
            crc32: crc32fast::hash(bytes),
        }
    }
}

impl std::fmt::Display for Digest {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{:08x}", self.bytes, self.crc32)
    }
}

thread_local! {
    /// The digests of the files read since `while_reading` began on this thread; None when no
    /// one is collecting. Scene loading runs on the calling thread (no pool reads a file).
    static COLLECTING: RefCell<Option<Vec<Digest>>> = const { RefCell::new(None) };
}

/// Runs `f`, and returns with its result the digests of the files it read, in the order it
/// read them (every read: a loader reads the same inputs in the same order, so the order says
/// which file each digest is, and two textures that swapped contents differ).
pub fn while_reading<T>(f: impl FnOnce() -> T) -> (T, Vec<Digest>) {
    let outer = COLLECTING.with(|c| c.borrow_mut().replace(Vec::new()));
    let result = f();
    let read = COLLECTING.with(|c| std::mem::replace(&mut *c.borrow_mut(), outer));
    (result, read.unwrap_or_default())
}

/// Notes a file's content, if someone on this thread is collecting.
pub(super) fn note(bytes: &[u8]) {
    COLLECTING.with(|c| {
        if let Some(read) = c.borrow_mut().as_mut() {
            read.push(Digest::of(bytes));
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_files_read_inside_are_collected_in_the_order_read() {
        let dir = std::env::temp_dir().join(format!("specchio-digest-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (a, b) = (dir.join("a"), dir.join("b"));
        std::fs::write(&a, b"room").unwrap();
        std::fs::write(&b, b"mirror").unwrap();
        let read = |p: &std::path::Path| super::super::read_regular_file(p, 100).unwrap();
        read(&a); // outside: not collected
        let ((), digests) = while_reading(|| {
            read(&b);
            read(&a);
            read(&b);
        });
        let (room, mirror) = (Digest::of(b"room"), Digest::of(b"mirror"));
        assert_eq!(digests, vec![mirror, room, mirror]);
        // The standard CRC-32 check value (ISO-HDLC): an independent known answer.
        assert_eq!(Digest::of(b"123456789").crc32, 0xcbf4_3926);
        assert_eq!(
            Digest::of(b"room").to_string(),
            format!("4:{:08x}", Digest::of(b"room").crc32)
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
