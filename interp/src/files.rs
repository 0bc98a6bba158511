//! Reading files whose size and kind klar does not control (programs, tables, machine files):
//! anything that is not a regular file is refused before it is opened (a FIFO or a device
//! could block or never end), and whole-file reads stop at a stated size.

use std::io::{self, Read};
use std::path::Path;

/// What `path` is when it is not a regular file (`a folder`, `a FIFO`, `a device`, …); None for
/// a regular file or when its kind cannot be read (opening it then says why).
pub fn not_a_file(path: &std::path::Path) -> Option<&'static str> {
    let kind = std::fs::metadata(path).ok()?.file_type();
    if kind.is_file() {
        return None;
    }
    if kind.is_dir() {
        return Some("a folder");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return Some("a FIFO");
        }
        if kind.is_char_device() || kind.is_block_device() {
            return Some("a device");
        }
        if kind.is_socket() {
            return Some("a socket");
        }
    }
    Some("neither a file nor a folder")
}

/// Reads a whole regular file of at most `max` bytes; anything else (not a regular file, or
/// larger) is an error that says so, and never more than `max + 1` bytes are read.
pub fn read_bounded(path: &Path, max: u64) -> io::Result<Vec<u8>> {
    if let Some(kind) = not_a_file(path) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("not a regular file ({kind})"),
        ));
    }
    let file = std::fs::File::open(path)?;
    let mut buf = Vec::new();
    file.take(max.saturating_add(1)).read_to_end(&mut buf)?;
    if buf.len() as u64 > max {
        return Err(io::Error::new(
            io::ErrorKind::InvalidData,
            format!("larger than {max} bytes (klar's limit for this kind of file)"),
        ));
    }
    Ok(buf)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folders_and_devices_are_refused_and_sizes_bounded() {
        let dir = std::env::temp_dir();
        assert_eq!(not_a_file(&dir), Some("a folder"));
        #[cfg(unix)]
        {
            assert_eq!(not_a_file(Path::new("/dev/zero")), Some("a device"));
            let e = read_bounded(Path::new("/dev/zero"), 10).unwrap_err();
            assert!(
                e.to_string().contains("not a regular file (a device)"),
                "{e}"
            );
        }
        let f = dir.join(format!("klar-bounded-{}.txt", std::process::id()));
        std::fs::write(&f, b"0123456789").unwrap();
        assert_eq!(not_a_file(&f), None);
        assert_eq!(read_bounded(&f, 10).unwrap(), b"0123456789");
        let e = read_bounded(&f, 9).unwrap_err();
        assert!(e.to_string().contains("larger than 9 bytes"), "{e}");
        std::fs::remove_file(&f).unwrap();
    }
}
