//! [`read_input_text`]: the one way this program reads a user's input file (a scene, a URDF, a
//! solution and its internals, a torque series, an initial state). The text is bounded by
//! [`MAX_INPUT_BYTES`], so that a path to a device or a stream that never ends (`/dev/zero`,
//! `/dev/urandom`) or a file far larger than any input is refused with an error instead of
//! reading until the machine's memory is exhausted. Pipes and process substitutions still work.

use std::io::{self, Read};
use std::path::Path;

/// The largest input file this program reads, in bytes (256 MiB). The largest inputs it writes
/// itself, a refined optimum's `solution.json` and a long torque series, are a few MB.
pub const MAX_INPUT_BYTES: u64 = 256 << 20;

/// The UTF-8 text of the file at `path`, or an error when it cannot be read, is not UTF-8, or
/// holds more than [`MAX_INPUT_BYTES`] (the error says so; the caller names the file).
pub fn read_input_text(path: impl AsRef<Path>) -> io::Result<String> {
    read_bounded(std::fs::File::open(path)?, MAX_INPUT_BYTES)
}

fn read_bounded(source: impl Read, limit: u64) -> io::Result<String> {
    let mut bytes = Vec::new();
    source.take(limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(io::Error::new(
            io::ErrorKind::InvalidData,
            format!(
                "more than {} MiB, larger than any input of this program (a device or a \
                 stream that does not end?)",
                limit >> 20
            ),
        ));
    }
    String::from_utf8(bytes)
        .map_err(|_| io::Error::new(io::ErrorKind::InvalidData, "not UTF-8 text"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stream_beyond_the_limit_is_refused_after_the_limit() {
        let endless = io::repeat(b' ');
        let e = read_bounded(endless, 4 << 20).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidData);
        assert!(e.to_string().contains("more than 4 MiB"), "{e}");
        assert_eq!(
            read_bounded(&b"name = \"x\""[..], 10).unwrap(),
            "name = \"x\""
        );
        assert!(read_bounded(&b"12345678901"[..], 10).is_err());
    }

    #[test]
    fn bytes_that_are_not_utf8_are_refused() {
        let e = read_bounded(&[0xff, 0xfe, b'a'][..], 10).unwrap_err();
        assert!(e.to_string().contains("not UTF-8"), "{e}");
    }
}
