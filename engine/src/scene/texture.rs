//! TEMPORARY stub.
#[derive(Debug, Clone)]
pub struct TextureData {
    pub path: std::path::PathBuf,
    pub width: u32,
    pub height: u32,
    pub rgba8: Vec<u8>,
}
