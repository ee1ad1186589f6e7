//! Recordings of a world session: the frames of the protocol, as they
//! crossed the socket, with their direction and time (`pushlearn ctl
//! record` writes them, `pushlearn-sim replay` serves them). The byte layout
//! is documented in `docs/protocol.md` §9:
//!
//! ```text
//! header:  "PLRECORD" | version u32 BE | flags u32 BE | Hello frame
//! record:  direction u8 | time u64 BE (ns since the start) | frame
//! frame:   length u32 BE | that many bytes of one envelope (as on the wire)
//! ```
//!
//! A reader refuses a file that is not a recording, or of another version,
//! with an error saying which; a file cut short (a recorder killed
//! mid-write) yields every whole record and says where it was cut.

use std::io::{self, Write};
use std::path::Path;
use std::time::Duration;

use prost::Message;

use crate::wire::{pb, LENGTH_PREFIX_SIZE, MAX_FRAME_SIZE};

/// The first 8 bytes of every recording.
pub const MAGIC: [u8; 8] = *b"PLRECORD";

/// The format version this build writes and reads.
pub const VERSION: u32 = 1;

/// Flag bit: the file holds the client's frames too (a recording proxy),
/// not only what the world sent to an observer.
pub const FLAG_COMMANDS: u32 = 1;

/// Magic, version and flags.
const FIXED_HEADER: usize = MAGIC.len() + 4 + 4;

/// Direction byte and timestamp in front of each record's frame.
const RECORD_PREFIX: usize = 1 + 8;

/// Who sent a recorded frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// A `ServerMessage`, world to client (byte 0).
    FromWorld,
    /// A `ClientMessage`, client to world (byte 1).
    FromClient,
}

impl Direction {
    fn byte(self) -> u8 {
        match self {
            Direction::FromWorld => 0,
            Direction::FromClient => 1,
        }
    }
}

/// A recorded frame, decoded.
#[derive(Debug, Clone, PartialEq)]
pub enum Frame {
    /// What the world sent.
    World(pb::ServerMessage),
    /// What the client sent.
    Client(pb::ClientMessage),
}

/// One record: when, and what.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// Time since the recording started.
    pub at: Duration,
    /// The frame.
    pub frame: Frame,
}

/// What the header says.
#[derive(Debug, Clone, PartialEq)]
pub struct Header {
    /// The client's frames are recorded too ([`FLAG_COMMANDS`]).
    pub commands: bool,
    /// The world's Hello to the recorded client.
    pub hello: pb::Hello,
}

/// A whole recording as read.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// The header.
    pub header: Header,
    /// Every whole record, in file order.
    pub records: Vec<Record>,
    /// Where the file was cut short, if it was.
    pub truncated: Option<Truncation>,
}

/// A file that ends inside a record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Truncation {
    /// Byte offset of the incomplete record.
    pub offset: usize,
    /// Its bytes present.
    pub present: usize,
}

/// Why a file is not a readable recording.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// The file cannot be read or written.
    #[error("{path}: {reason}")]
    Io {
        /// The file.
        path: String,
        /// The cause (in the message, not a `source`, so it is printed once).
        reason: io::Error,
    },
    /// Does not start with [`MAGIC`].
    #[error("{path}: not a pushlearn recording (it starts with \"{found}\", a recording with \"PLRECORD\")")]
    BadMagic {
        /// The file.
        path: String,
        /// Its first bytes, as text where printable.
        found: String,
    },
    /// A version this build does not read.
    #[error(
        "{path}: recording format version {found}, but this build reads version {VERSION} only"
    )]
    UnsupportedVersion {
        /// The file.
        path: String,
        /// The file's version.
        found: u32,
    },
    /// Structurally wrong: a header cut short, a frame that does not
    /// decode, an unknown direction byte.
    #[error("{path}: corrupt at byte {offset}: {problem}")]
    Corrupt {
        /// The file.
        path: String,
        /// Where.
        offset: usize,
        /// What is wrong.
        problem: String,
    },
}

/// Writes a recording: the header at once, then one record per call.
#[derive(Debug)]
pub struct RecordingWriter<W: Write> {
    out: W,
}

impl<W: Write> RecordingWriter<W> {
    /// Writes the header: `hello_frame` is the world's Hello envelope as it
    /// came off the wire (without its length prefix).
    pub fn new(mut out: W, commands: bool, hello_frame: &[u8]) -> io::Result<Self> {
        out.write_all(&MAGIC)?;
        out.write_all(&VERSION.to_be_bytes())?;
        let flags = if commands { FLAG_COMMANDS } else { 0 };
        out.write_all(&flags.to_be_bytes())?;
        write_frame(&mut out, hello_frame)?;
        Ok(Self { out })
    }

    /// Appends one frame (an envelope without its length prefix) sent in
    /// `direction` at `at` since the start.
    pub fn record(&mut self, direction: Direction, at: Duration, frame: &[u8]) -> io::Result<()> {
        let nanos = u64::try_from(at.as_nanos()).unwrap_or(u64::MAX);
        self.out.write_all(&[direction.byte()])?;
        self.out.write_all(&nanos.to_be_bytes())?;
        write_frame(&mut self.out, frame)
    }

    /// Flushes and returns the writer.
    pub fn finish(mut self) -> io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

fn write_frame(out: &mut impl Write, frame: &[u8]) -> io::Result<()> {
    let len = u32::try_from(frame.len())
        .ok()
        .filter(|&l| l as usize <= MAX_FRAME_SIZE)
        .ok_or_else(|| {
            io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "a frame of {} bytes exceeds the protocol's maximum",
                    frame.len()
                ),
            )
        })?;
    out.write_all(&len.to_be_bytes())?;
    out.write_all(frame)
}

/// Reads the recording at `path` (see [`parse`]).
pub fn read_file(path: &Path) -> Result<Recording, RecordingError> {
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|reason| RecordingError::Io {
        path: name.clone(),
        reason,
    })?;
    parse(&bytes, &name)
}

/// Parses a recording's bytes; `path` names it in errors.
pub fn parse(bytes: &[u8], path: &str) -> Result<Recording, RecordingError> {
    let corrupt = |offset: usize, problem: String| RecordingError::Corrupt {
        path: path.to_owned(),
        offset,
        problem,
    };
    if bytes.len() < MAGIC.len() || bytes[..MAGIC.len()] != MAGIC {
        let head = &bytes[..bytes.len().min(MAGIC.len())];
        return Err(RecordingError::BadMagic {
            path: path.to_owned(),
            found: String::from_utf8_lossy(head).escape_debug().to_string(),
        });
    }
    let Some(fixed) = bytes.get(MAGIC.len()..FIXED_HEADER) else {
        return Err(corrupt(
            MAGIC.len(),
            "the header ends before its version and flags".into(),
        ));
    };
    let version = be_u32(&fixed[..4]);
    if version != VERSION {
        return Err(RecordingError::UnsupportedVersion {
            path: path.to_owned(),
            found: version,
        });
    }
    let flags = be_u32(&fixed[4..]);
    let Some((hello_bytes, mut offset)) = frame_at(bytes, FIXED_HEADER) else {
        return Err(corrupt(
            FIXED_HEADER,
            "the header ends inside the Hello frame".into(),
        ));
    };
    let hello = match pb::ServerMessage::decode(hello_bytes).map(|m| m.payload) {
        Ok(Some(pb::server_message::Payload::Hello(hello))) => hello,
        Ok(_) => {
            return Err(corrupt(
                FIXED_HEADER,
                "the header's frame is not a Hello".into(),
            ))
        }
        Err(err) => {
            return Err(corrupt(
                FIXED_HEADER,
                format!("the header's Hello does not decode: {err}"),
            ))
        }
    };
    let mut records = Vec::new();
    let mut truncated = None;
    while offset < bytes.len() {
        let start = offset;
        let Some(prefix) = bytes.get(start..start + RECORD_PREFIX) else {
            truncated = Some(Truncation {
                offset: start,
                present: bytes.len() - start,
            });
            break;
        };
        let at = Duration::from_nanos(u64::from_be_bytes(
            prefix[1..].try_into().unwrap_or_default(),
        ));
        let Some((frame, next)) = frame_at(bytes, start + RECORD_PREFIX) else {
            if too_large(bytes, start + RECORD_PREFIX) {
                return Err(corrupt(
                    start + RECORD_PREFIX,
                    format!("a frame length above the protocol's {MAX_FRAME_SIZE} bytes"),
                ));
            }
            truncated = Some(Truncation {
                offset: start,
                present: bytes.len() - start,
            });
            break;
        };
        let frame = match prefix[0] {
            0 => pb::ServerMessage::decode(frame).map(Frame::World),
            1 => pb::ClientMessage::decode(frame).map(Frame::Client),
            other => {
                return Err(corrupt(
                    start,
                    format!(
                        "record {}: direction byte {other} (expected 0 or 1)",
                        records.len() + 1
                    ),
                ))
            }
        }
        .map_err(|err| {
            corrupt(
                start,
                format!(
                    "record {}: the frame does not decode: {err}",
                    records.len() + 1
                ),
            )
        })?;
        records.push(Record { at, frame });
        offset = next;
    }
    Ok(Recording {
        header: Header {
            commands: flags & FLAG_COMMANDS != 0,
            hello,
        },
        records,
        truncated,
    })
}

fn be_u32(bytes: &[u8]) -> u32 {
    u32::from_be_bytes(bytes.try_into().unwrap_or_default())
}

/// The envelope of the frame at `offset` and the offset after it, if the
/// whole frame is there and within the protocol's limit.
fn frame_at(bytes: &[u8], offset: usize) -> Option<(&[u8], usize)> {
    let prefix = bytes.get(offset..offset + LENGTH_PREFIX_SIZE)?;
    let len = be_u32(prefix) as usize;
    if len > MAX_FRAME_SIZE {
        return None;
    }
    let start = offset + LENGTH_PREFIX_SIZE;
    let frame = bytes.get(start..start + len)?;
    Some((frame, start + len))
}

fn too_large(bytes: &[u8], offset: usize) -> bool {
    bytes
        .get(offset..offset + LENGTH_PREFIX_SIZE)
        .is_some_and(|prefix| be_u32(prefix) as usize > MAX_FRAME_SIZE)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hello() -> pb::Hello {
        pb::Hello {
            scene: "one_block".into(),
            step_size: 0.001,
            publish_rate: 100,
            timing_mode: "lockstep".into(),
            ..Default::default()
        }
    }

    fn sample() -> (Vec<u8>, Vec<Record>) {
        let hello_frame = pb::ServerMessage::from(hello()).encode_to_vec();
        let records = vec![
            Record {
                at: Duration::from_micros(5),
                frame: Frame::Client(pb::ClientMessage::move_(7, 0.0, 0.5)),
            },
            Record {
                at: Duration::from_millis(20),
                frame: Frame::World(pb::ServerMessage::from(pb::WorldState {
                    step: 10,
                    applied_seq: 7,
                    ..Default::default()
                })),
            },
            Record {
                at: Duration::from_millis(21),
                frame: Frame::Client(pb::ClientMessage::barrier(8)),
            },
        ];
        let mut writer = RecordingWriter::new(Vec::new(), true, &hello_frame).unwrap();
        for record in &records {
            let (direction, bytes) = match &record.frame {
                Frame::World(m) => (Direction::FromWorld, m.encode_to_vec()),
                Frame::Client(m) => (Direction::FromClient, m.encode_to_vec()),
            };
            writer.record(direction, record.at, &bytes).unwrap();
        }
        (writer.finish().unwrap(), records)
    }

    #[test]
    fn a_recording_round_trips() {
        let (bytes, records) = sample();
        assert_eq!(&bytes[..8], b"PLRECORD");
        assert_eq!(&bytes[8..16], &[0, 0, 0, 1, 0, 0, 0, 1]);
        let read = parse(&bytes, "r.plrec").unwrap();
        assert_eq!(
            read.header,
            Header {
                commands: true,
                hello: hello()
            }
        );
        assert_eq!(read.records, records);
        assert_eq!(read.truncated, None);
    }

    #[test]
    fn a_truncated_tail_keeps_the_whole_records() {
        let (bytes, records) = sample();
        // Every cut inside the last record keeps the first two.
        let last_len = RECORD_PREFIX
            + LENGTH_PREFIX_SIZE
            + pb::ClientMessage::barrier(8).encode_to_vec().len();
        let last = bytes.len() - last_len;
        for cut in last + 1..bytes.len() {
            let read = parse(&bytes[..cut], "r.plrec").unwrap();
            assert_eq!(read.records, records[..2], "cut at {cut}");
            assert_eq!(
                read.truncated,
                Some(Truncation {
                    offset: last,
                    present: cut - last
                })
            );
        }
        assert_eq!(parse(&bytes[..last], "r.plrec").unwrap().truncated, None);
    }

    #[test]
    fn bad_magic_version_and_garbage_are_named() {
        let (bytes, _) = sample();
        let message = |bytes: &[u8]| parse(bytes, "r.plrec").unwrap_err().to_string();
        assert_eq!(
            message(b"GIF89a\x01\x02garbage"),
            "r.plrec: not a pushlearn recording (it starts with \"GIF89a\\u{1}\\u{2}\", a recording with \"PLRECORD\")"
        );
        assert!(message(b"").contains("not a pushlearn recording"));
        let mut other = bytes.clone();
        other[11] = 2;
        assert_eq!(
            message(&other),
            "r.plrec: recording format version 2, but this build reads version 1 only"
        );
        assert!(message(&bytes[..12]).contains("corrupt at byte 8: the header ends"));
        assert!(message(&bytes[..20]).contains("the header ends inside the Hello frame"));
        let header = FIXED_HEADER
            + LENGTH_PREFIX_SIZE
            + pb::ServerMessage::from(hello()).encode_to_vec().len();
        let mut direction = bytes.clone();
        direction[header] = 9;
        assert!(
            message(&direction).contains(&format!(
                "corrupt at byte {header}: record 1: direction byte 9"
            )),
            "{}",
            message(&direction)
        );
        let mut huge = bytes;
        huge[header + RECORD_PREFIX..header + RECORD_PREFIX + 4].copy_from_slice(&[0xff; 4]);
        assert!(
            message(&huge).contains("frame length above"),
            "{}",
            message(&huge)
        );
    }

    #[test]
    fn a_missing_file_is_named() {
        let err = read_file(Path::new("/nonexistent/r.plrec")).unwrap_err();
        assert!(
            err.to_string().starts_with("/nonexistent/r.plrec: "),
            "{err}"
        );
    }
}
