//! The journal's records: `length u32 | CRC-32 u32 | index u64 | payload`,
//! little-endian, the checksum covering index and payload; the payload is an
//! [`Entry`].

use learner::{Frame, Observation};

/// Record header: payload length (u32), CRC-32 of index and payload (u32),
/// index (u64), all little-endian.
pub(super) const RECORD_HEADER: usize = 16;

/// Largest record payload accepted on reading: far above any world's state
/// (a frame is about 70 bytes per body); a larger length is damage.
const MAX_RECORD: usize = 1 << 20;

const ENTRY_STATE: u8 = 1;
const ENTRY_RESYNC: u8 = 2;

/// CRC-32 (IEEE 802.3, reflected, as zlib's `crc32`) of `parts` in turn.
pub(super) fn crc32(parts: &[&[u8]]) -> u32 {
    let mut hasher = crc32fast::Hasher::new();
    for part in parts {
        hasher.update(part);
    }
    hasher.finalize()
}

/// One journal record's content.
#[derive(Clone, Debug, PartialEq)]
pub enum Entry {
    /// A world state handed to
    /// [`Learner::on_state`](crate::learn::Learner::on_state).
    State(Frame),
    /// [`Learner::resync`](crate::learn::Learner::resync): the connection to the world was lost or the
    /// daemon restarted.
    Resync,
}

/// Appends record `index` holding `entry` (a frame, or `None` for a resync).
pub(super) fn encode_record(index: u64, frame: Option<&Frame>, out: &mut Vec<u8>) {
    let start = out.len();
    out.extend_from_slice(&[0; RECORD_HEADER]);
    match frame {
        None => out.push(ENTRY_RESYNC),
        Some(frame) => {
            out.push(ENTRY_STATE);
            // Bodies and names are bounded by the 16 MiB wire frame.
            out.extend_from_slice(&(frame.objects.len() as u32).to_le_bytes());
            for o in &frame.objects {
                out.extend_from_slice(&o.id.to_le_bytes());
                out.extend_from_slice(&(o.name.len() as u32).to_le_bytes());
                out.extend_from_slice(o.name.as_bytes());
                for v in o.position.iter().chain(&o.orientation) {
                    out.extend_from_slice(&v.to_bits().to_le_bytes());
                }
            }
        }
    }
    let payload_len = out.len() - start - RECORD_HEADER;
    let index_bytes = index.to_le_bytes();
    let crc = crc32(&[&index_bytes, &out[start + RECORD_HEADER..]]);
    out[start..start + 4].copy_from_slice(&(payload_len as u32).to_le_bytes());
    out[start + 4..start + 8].copy_from_slice(&crc.to_le_bytes());
    out[start + 8..start + 16].copy_from_slice(&index_bytes);
}

/// A little-endian reader over untrusted bytes.
pub(super) struct Cursor<'a> {
    pub(super) bytes: &'a [u8],
}

impl<'a> Cursor<'a> {
    pub(super) fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        if self.bytes.len() < n {
            return None;
        }
        let (head, rest) = self.bytes.split_at(n);
        self.bytes = rest;
        Some(head)
    }

    pub(super) fn array<const N: usize>(&mut self) -> Option<[u8; N]> {
        self.take(N)?.try_into().ok()
    }

    pub(super) fn u32(&mut self) -> Option<u32> {
        self.array().map(u32::from_le_bytes)
    }

    fn f64(&mut self) -> Option<f64> {
        self.array().map(|b| f64::from_bits(u64::from_le_bytes(b)))
    }
}

/// Decodes a record's payload; `None` if it is not a well-formed entry.
/// Public for the fuzz target and its property-test mirror.
pub fn decode_entry(payload: &[u8]) -> Option<Entry> {
    let mut c = Cursor { bytes: payload };
    let entry = match c.array::<1>()?[0] {
        ENTRY_RESYNC => Entry::Resync,
        ENTRY_STATE => {
            let n = c.u32()? as usize;
            // Each body takes at least 64 bytes: a huge count is damage, and
            // must not reserve memory.
            if n > c.bytes.len() / 64 {
                return None;
            }
            let mut objects = Vec::with_capacity(n);
            for _ in 0..n {
                let id = c.u32()?;
                let len = c.u32()? as usize;
                let name = std::str::from_utf8(c.take(len)?).ok()?.to_owned();
                let mut v = [0.0; 7];
                for x in &mut v {
                    *x = c.f64()?;
                }
                objects.push(Observation {
                    name,
                    id,
                    position: [v[0], v[1], v[2]],
                    orientation: [v[3], v[4], v[5], v[6]],
                    shape: None,
                });
            }
            Entry::State(Frame { objects })
        }
        _ => return None,
    };
    c.bytes.is_empty().then_some(entry)
}

/// The outcome of reading a segment: its records in order, and where and why
/// reading stopped early, if it did.
#[derive(Debug, Default)]
pub struct SegmentRead {
    /// Index, entry and the byte offset just after the record.
    pub records: Vec<(u64, Entry, usize)>,
    /// Byte offset of the first bad record and why it is bad.
    pub bad: Option<(usize, String)>,
}

/// Reads journal records from `bytes` until the end or the first damaged
/// record. Public for the fuzz target and its property-test mirror.
pub fn read_records(bytes: &[u8]) -> SegmentRead {
    let mut read = SegmentRead::default();
    let mut at = 0;
    while at < bytes.len() {
        let rest = &bytes[at..];
        let bad = |reason: String| Some((at, reason));
        if rest.len() < RECORD_HEADER {
            read.bad = bad(format!(
                "a record header cut off after {} of {RECORD_HEADER} bytes",
                rest.len()
            ));
            break;
        }
        let word = |i: usize| u32::from_le_bytes([rest[i], rest[i + 1], rest[i + 2], rest[i + 3]]);
        let len = word(0) as usize;
        let crc = word(4);
        let index_bytes = &rest[8..16];
        let mut index = [0; 8];
        index.copy_from_slice(index_bytes);
        let index = u64::from_le_bytes(index);
        if len > MAX_RECORD {
            read.bad = bad(format!("a record length of {len} bytes (damage)"));
            break;
        }
        let Some(payload) = rest.get(RECORD_HEADER..RECORD_HEADER + len) else {
            read.bad = bad(format!(
                "record {index} cut off after {} of {len} bytes",
                rest.len() - RECORD_HEADER
            ));
            break;
        };
        if crc32(&[index_bytes, payload]) != crc {
            read.bad = bad(format!("record {index} fails its checksum"));
            break;
        }
        let Some(entry) = decode_entry(payload) else {
            read.bad = bad(format!(
                "record {index} has a valid checksum but no valid entry"
            ));
            break;
        };
        at += RECORD_HEADER + len;
        read.records.push((index, entry, at));
    }
    read
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;
    use crate::learn::state::testing::frames;

    #[test]
    fn crc32_is_the_ieee_checksum() {
        assert_eq!(crc32(&[b"123456789"]), 0xCBF4_3926);
        assert_eq!(crc32(&[b"1234", b"56789"]), 0xCBF4_3926);
    }

    #[test]
    fn records_keep_every_bit_of_a_frame() {
        let mut f = frames(3).pop().unwrap();
        f.objects[0].position[0] = -0.0;
        f.objects[0].orientation[1] = f64::from_bits(0x7ff8_0000_0000_1234);
        f.objects[0].name = "Aktuator-ä".into();
        let mut bytes = Vec::new();
        encode_record(41, Some(&f), &mut bytes);
        encode_record(42, None, &mut bytes);
        let read = read_records(&bytes);
        assert_eq!(read.bad, None);
        assert_eq!(read.records.len(), 2);
        let (index, Entry::State(back), _) = &read.records[0] else {
            panic!("{:?}", read.records[0]);
        };
        assert_eq!(*index, 41);
        let bits = |f: &Frame| -> Vec<u64> {
            f.objects
                .iter()
                .flat_map(|o| o.position.iter().chain(&o.orientation).map(|v| v.to_bits()))
                .collect()
        };
        assert_eq!(bits(back), bits(&f));
        assert_eq!(back.objects[0].name, "Aktuator-ä");
        assert_eq!(read.records[1].0, 42);
        assert_eq!(read.records[1].1, Entry::Resync);
        assert_eq!(read.records[1].2, bytes.len());
    }

    /// The format on disk, written out by hand from the layout (with
    /// Python's `zlib.crc32` for the checksums): files written by earlier
    /// builds must go on verifying.
    #[test]
    fn records_are_byte_for_byte_the_format_on_disk() {
        let actuator = Observation {
            name: "actuator".into(),
            id: 8,
            position: [0.0, 0.25, 0.03],
            orientation: [0.0, 0.0, 0.0, 1.0],
            shape: None,
        };
        let mut bytes = Vec::new();
        encode_record(
            7,
            Some(&Frame {
                objects: vec![actuator],
            }),
            &mut bytes,
        );
        encode_record(8, None, &mut bytes);
        let hex: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(
            hex,
            "4d000000bd77e7620700000000000000010100000008000000080000006163747561746f72\
             0000000000000000000000000000d03fb81e85eb51b89e3f0000000000000000000000000000\
             00000000000000000000000000000000f03f010000009ad7dfb3080000000000000002"
        );
    }

    /// The `journal` fuzz target's kept inputs, through its property: damage
    /// is found exactly where the good records end.
    #[test]
    fn the_fuzzers_kept_journals_are_read_up_to_their_damage() {
        let kept = sim_plugin::untrusted::kept_fuzz_inputs("journal");
        assert!(
            kept.len() >= 10,
            "fuzz/corpus/journal has {} inputs",
            kept.len()
        );
        for (path, bytes) in kept {
            let read = read_records(&bytes);
            let end = read.records.last().map_or(0, |r| r.2);
            match read.bad {
                Some((offset, _)) => assert_eq!(offset, end, "{}", path.display()),
                None => assert_eq!(end, bytes.len(), "{}", path.display()),
            }
        }
    }

    proptest! {
        /// The journal reader takes any bytes without panicking, and never
        /// returns a record it did not verify (the same code path as the
        /// `journal` fuzz target).
        #[test]
        fn any_bytes_read_as_a_journal_are_safe(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
            let read = read_records(&bytes);
            let mut end = 0;
            for (_, _, e) in &read.records {
                prop_assert!(*e > end && *e <= bytes.len());
                end = *e;
            }
            match read.bad {
                Some((offset, _)) => prop_assert_eq!(offset, end),
                None => prop_assert_eq!(end, bytes.len()),
            }
        }

        #[test]
        fn any_frame_survives_the_journal(
            names in proptest::collection::vec("[a-zA-Z_]{0,12}", 0..5),
            values in proptest::collection::vec(any::<u64>(), 35),
            index in any::<u64>(),
        ) {
            let objects = names.iter().enumerate().map(|(i, name)| Observation {
                name: name.clone(),
                id: i as u32,
                position: [0, 1, 2].map(|k| f64::from_bits(values[7 * i + k])),
                orientation: [3, 4, 5, 6].map(|k| f64::from_bits(values[7 * i + k])),
                shape: None,
            }).collect();
            let f = Frame { objects };
            let mut bytes = Vec::new();
            encode_record(index, Some(&f), &mut bytes);
            let read = read_records(&bytes);
            prop_assert!(read.bad.is_none());
            let Entry::State(back) = &read.records[0].1 else { panic!("not a state") };
            prop_assert_eq!(format!("{:?}", back.objects.iter().map(|o| (&o.name, o.id, o.position.map(f64::to_bits), o.orientation.map(f64::to_bits))).collect::<Vec<_>>()),
                format!("{:?}", f.objects.iter().map(|o| (&o.name, o.id, o.position.map(f64::to_bits), o.orientation.map(f64::to_bits))).collect::<Vec<_>>()));
        }
    }
}
