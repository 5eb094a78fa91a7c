//! Files refused before they are read: a device such as `/dev/zero`, a pipe, a folder, or a
//! file larger than its kind may be. An error says what is wrong, and the caller names the
//! file.

use std::io::Read;
use std::path::Path;

/// Largest scene file (TOML, Mitsuba XML, pbrt): the parsers hold the text and a tree several
/// times its size, and a scene of more than 64 MiB of text keeps its geometry where it
/// belongs, in OBJ or PLY files.
pub const SCENE_FILE_LIMIT: u64 = 64 << 20;

/// Largest mesh file (OBJ, PLY): both readers hold the whole file, then its vertices and
/// triangles, about three times its size; 2 GiB is some 80 million triangles, more than the
/// BVH builder and a render of this tool handle in hours.
pub const MESH_FILE_LIMIT: u64 = 2 << 30;

/// Largest texture image file (compressed), and the most bytes its decoded pixels may take:
/// 16384 x 16384 RGBA at 8 bits is 1 GiB; the texture kept is reduced to
/// [`MAX_TEXTURE_SIDE`](ppm_core::scene::MAX_TEXTURE_SIDE) anyway.
pub const TEXTURE_FILE_LIMIT: u64 = 1 << 30;

/// Reads a file of at most `limit` bytes, refusing anything that is not a regular file (a
/// device such as `/dev/zero`, a pipe, a folder) before reading a byte. The error says what is
/// wrong, without the path (the caller names the file).
pub fn read_limited(path: &Path, limit: u64) -> Result<Vec<u8>, String> {
    let mut file = std::fs::File::open(path).map_err(io_reason)?;
    let size = regular_size(&file.metadata().map_err(io_reason)?, limit)?;
    let mut bytes = Vec::with_capacity(size as usize);
    file.by_ref()
        .take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(io_reason)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(bytes.len() as u64, limit));
    }
    Ok(bytes)
}

/// [`read_limited`] as UTF-8 text.
pub fn read_text_limited(path: &Path, limit: u64) -> Result<String, String> {
    String::from_utf8(read_limited(path, limit)?)
        .map_err(|e| format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()))
}

/// Checks, before a reader that opens `path` itself (tobj), that it is a regular file of at
/// most `limit` bytes.
pub fn check_file_size(path: &Path, limit: u64) -> Result<(), String> {
    let meta = std::fs::metadata(path).map_err(io_reason)?;
    regular_size(&meta, limit).map(|_| ())
}

/// What the operating system said, with the commonest case in words.
fn io_reason(e: std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".into(),
        _ => e.to_string(),
    }
}

fn regular_size(meta: &std::fs::Metadata, limit: u64) -> Result<u64, String> {
    if !meta.is_file() {
        return Err(if meta.is_dir() {
            "is a folder, not a file".into()
        } else {
            "is not a regular file (a device or a pipe never ends)".into()
        });
    }
    if meta.len() > limit {
        return Err(too_large(meta.len(), limit));
    }
    Ok(meta.len())
}

fn too_large(size: u64, limit: u64) -> String {
    format!("is {size} bytes; this kind of file may have at most {limit}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_device_or_an_oversized_file_is_refused_before_reading() {
        if cfg!(target_os = "linux") {
            let err = read_limited(Path::new("/dev/zero"), SCENE_FILE_LIMIT).unwrap_err();
            assert_eq!(err, "is not a regular file (a device or a pipe never ends)");
        }
        let dir = std::env::temp_dir();
        assert_eq!(
            check_file_size(&dir, MESH_FILE_LIMIT).unwrap_err(),
            "is a folder, not a file"
        );
        let path = dir.join(format!("ppm-limits-{}.txt", std::process::id()));
        std::fs::write(&path, "0123456789").unwrap();
        let small = read_limited(&path, 10);
        let large = read_limited(&path, 9);
        std::fs::remove_file(&path).ok();
        assert_eq!(small.unwrap().len(), 10);
        assert_eq!(
            large.unwrap_err(),
            "is 10 bytes; this kind of file may have at most 9"
        );
    }
}
