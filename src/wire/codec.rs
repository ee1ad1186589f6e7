//! Framing: a 4-byte big-endian length prefix, then one protobuf envelope.
//!
//! Built on tokio-util's [`LengthDelimitedCodec`] so that the length handling
//! (and its refusal of oversized prefixes) is the well-tested one; this module
//! only adds the protobuf step and typed errors.

use std::io;
use std::marker::PhantomData;

use bytes::{Bytes, BytesMut};
use prost::Message;
use tokio_util::codec::{Decoder, Encoder, LengthDelimitedCodec, LengthDelimitedCodecError};

use super::pb;

/// Largest envelope, in bytes, that may follow a length prefix (16 MiB).
///
/// A world state is a few hundred bytes, so the limit is only there to stop a
/// corrupt or hostile length prefix from making the reader allocate gigabytes:
/// a larger prefix is refused as soon as its 4 bytes have arrived, before any
/// buffer for the payload is reserved. The limit is part of the protocol
/// (`docs/protocol.md`); both directions enforce it.
pub const MAX_FRAME_SIZE: usize = 16 * 1024 * 1024;

/// Size of the big-endian length prefix in front of every envelope.
pub const LENGTH_PREFIX_SIZE: usize = 4;

/// Why a frame could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum WireError {
    /// A length prefix (or an outgoing message) above [`MAX_FRAME_SIZE`].
    #[error("frame of {len} bytes exceeds the maximum frame size of {max} bytes")]
    FrameTooLarge {
        /// The announced (or attempted) length.
        len: u64,
        /// [`MAX_FRAME_SIZE`].
        max: usize,
    },
    /// A complete frame whose bytes are not a valid envelope.
    #[error("undecodable frame: {0}")]
    Decode(prost::DecodeError),
    /// The peer closed the connection part-way through a frame.
    #[error("connection closed in the middle of a frame ({buffered} bytes of it were received)")]
    Truncated {
        /// Bytes of the incomplete frame received, prefix included.
        buffered: usize,
    },
    /// The transport failed.
    #[error("i/o error: {0}")]
    Io(io::Error),
}

// Written out rather than `#[from]`: that would also make the cause the
// error's `source`, and error-chain printers would show its text twice.
impl From<prost::DecodeError> for WireError {
    fn from(err: prost::DecodeError) -> Self {
        WireError::Decode(err)
    }
}

impl From<io::Error> for WireError {
    fn from(err: io::Error) -> Self {
        WireError::Io(err)
    }
}

impl WireError {
    /// The `Error` a world sends before closing a connection that produced
    /// this error, or `None` if nothing can or need be said (the peer is gone
    /// or the transport broke). The message carries `seq = 0`: no command
    /// could be identified.
    pub fn error_reply(&self) -> Option<pb::ServerMessage> {
        match self {
            WireError::FrameTooLarge { .. } | WireError::Decode(_) => Some(
                pb::ServerMessage::error(0, pb::error::Kind::MalformedFrame, self.to_string()),
            ),
            WireError::Truncated { .. } | WireError::Io(_) => None,
        }
    }
}

/// The framing alone, envelopes left as bytes: for a proxy or recorder that
/// must pass frames on unchanged (decoding and re-encoding would drop fields
/// a newer peer added). Enforces [`MAX_FRAME_SIZE`] like the typed codecs.
pub fn raw_frame_codec() -> LengthDelimitedCodec {
    length_codec()
}

fn length_codec() -> LengthDelimitedCodec {
    LengthDelimitedCodec::builder()
        .length_field_length(LENGTH_PREFIX_SIZE)
        .big_endian()
        .max_frame_length(MAX_FRAME_SIZE)
        .new_codec()
}

/// Decodes frames into envelopes of type `T` (`pb::ClientMessage` in the
/// world, `pb::ServerMessage` in a client).
#[derive(Debug)]
pub struct FrameDecoder<T> {
    frames: LengthDelimitedCodec,
    /// The payload length of a frame whose prefix the inner codec has already
    /// consumed: the stream is then mid-frame even if no bytes are buffered.
    in_frame: Option<u64>,
    _message: PhantomData<fn() -> T>,
}

impl<T> Default for FrameDecoder<T> {
    fn default() -> Self {
        Self {
            frames: length_codec(),
            in_frame: None,
            _message: PhantomData,
        }
    }
}

impl<T> FrameDecoder<T> {
    /// A decoder enforcing [`MAX_FRAME_SIZE`].
    pub fn new() -> Self {
        Self::default()
    }
}

/// The length prefix at the front of `src`, which holds at least
/// [`LENGTH_PREFIX_SIZE`] bytes.
fn peek_length(src: &BytesMut) -> u64 {
    let mut prefix = [0u8; LENGTH_PREFIX_SIZE];
    prefix.copy_from_slice(&src[..LENGTH_PREFIX_SIZE]);
    u64::from(u32::from_be_bytes(prefix))
}

impl<T: Message + Default> Decoder for FrameDecoder<T> {
    type Item = T;
    type Error = WireError;

    fn decode(&mut self, src: &mut BytesMut) -> Result<Option<T>, WireError> {
        // Before the inner codec runs, a complete prefix at the front is the
        // next frame's: read it for error messages and mid-frame tracking.
        let announced =
            (self.in_frame.is_none() && src.len() >= LENGTH_PREFIX_SIZE).then(|| peek_length(src));
        let frame = match self.frames.decode(src) {
            Ok(Some(frame)) => frame,
            Ok(None) => {
                self.in_frame = self.in_frame.or(announced);
                return Ok(None);
            }
            Err(err)
                if err
                    .get_ref()
                    .is_some_and(|e| e.is::<LengthDelimitedCodecError>()) =>
            {
                return Err(WireError::FrameTooLarge {
                    len: announced.unwrap_or_default(),
                    max: MAX_FRAME_SIZE,
                });
            }
            Err(err) => return Err(WireError::Io(err)),
        };
        self.in_frame = None;
        Ok(Some(T::decode(frame.freeze())?))
    }

    fn decode_eof(&mut self, src: &mut BytesMut) -> Result<Option<T>, WireError> {
        match self.decode(src)? {
            Some(message) => Ok(Some(message)),
            None if src.is_empty() && self.in_frame.is_none() => Ok(None),
            None => {
                let prefix = if self.in_frame.is_some() {
                    LENGTH_PREFIX_SIZE
                } else {
                    0
                };
                Err(WireError::Truncated {
                    buffered: prefix + src.len(),
                })
            }
        }
    }
}

/// Encodes envelopes of type `T` into frames.
#[derive(Debug)]
pub struct FrameEncoder<T> {
    frames: LengthDelimitedCodec,
    _message: PhantomData<fn(&T)>,
}

impl<T> Default for FrameEncoder<T> {
    fn default() -> Self {
        Self {
            frames: length_codec(),
            _message: PhantomData,
        }
    }
}

impl<T> FrameEncoder<T> {
    /// An encoder enforcing [`MAX_FRAME_SIZE`].
    pub fn new() -> Self {
        Self::default()
    }
}

impl<T: Message> Encoder<&T> for FrameEncoder<T> {
    type Error = WireError;

    fn encode(&mut self, message: &T, dst: &mut BytesMut) -> Result<(), WireError> {
        let len = message.encoded_len();
        if len > MAX_FRAME_SIZE {
            return Err(WireError::FrameTooLarge {
                len: len as u64,
                max: MAX_FRAME_SIZE,
            });
        }
        self.frames
            .encode(Bytes::from(message.encode_to_vec()), dst)?;
        Ok(())
    }
}

/// One complete frame (length prefix and envelope) for `message`: for
/// writing the same bytes to many peers, and for documentation and tests.
pub fn encode_frame<T: Message>(message: &T) -> Result<Bytes, WireError> {
    let mut dst = BytesMut::new();
    FrameEncoder::new().encode(message, &mut dst)?;
    Ok(dst.freeze())
}

/// Decodes a whole byte stream the way a connection reads it until the peer
/// closes: the envelopes up to the first bad frame, and that frame's error
/// (a stream cut mid-frame is [`WireError::Truncated`]). Never panics on any
/// input: the code path under fuzzing (`docs/reliability.md`).
pub fn decode_stream<T: Message + Default>(bytes: &[u8]) -> (Vec<T>, Option<WireError>) {
    let mut decoder = FrameDecoder::<T>::new();
    let mut buf = BytesMut::from(bytes);
    let mut out = Vec::new();
    loop {
        match decoder.decode_eof(&mut buf) {
            Ok(Some(message)) => out.push(message),
            Ok(None) => return (out, None),
            Err(err) => return (out, Some(err)),
        }
    }
}

#[cfg(test)]
mod tests {
    use bytes::BufMut;
    use proptest::prelude::*;

    use super::*;
    use crate::wire::pb::{ClientMessage, ServerMessage};

    fn decode_all<T: Message + Default>(bytes: &[u8]) -> Result<Vec<T>, WireError> {
        match decode_stream(bytes) {
            (messages, None) => Ok(messages),
            (_, Some(err)) => Err(err),
        }
    }

    /// An Error envelope whose encoding is exactly `size` bytes long.
    fn server_message_of_size(size: usize) -> ServerMessage {
        let mut text_len = size;
        loop {
            let message =
                ServerMessage::error(7, pb::error::Kind::Unspecified, "x".repeat(text_len));
            let len = message.encoded_len();
            if len == size {
                return message;
            }
            // Tag and length varints make the envelope a few bytes longer than
            // the text; converge from above.
            text_len -= len.saturating_sub(size).max(1);
        }
    }

    #[test]
    fn frame_is_big_endian_length_then_envelope() {
        let message = ClientMessage::reset(3);
        let frame = encode_frame(&message).unwrap();
        let body = message.encode_to_vec();
        assert_eq!(&frame[..4], &(body.len() as u32).to_be_bytes());
        assert_eq!(&frame[4..], &body[..]);
    }

    #[test]
    fn frames_round_trip_back_to_back() {
        let messages = vec![
            ClientMessage::move_(1, 0.1, -0.5),
            ClientMessage::pause(2),
            ClientMessage::set_pose(3, "blockA", [0.1, 0.25, 0.05], 0.3),
            ClientMessage::barrier(4),
            ClientMessage::publish_rate(5, 10),
            ClientMessage::advance(6),
        ];
        let mut stream = BytesMut::new();
        for message in &messages {
            stream.extend_from_slice(&encode_frame(message).unwrap());
        }
        assert_eq!(decode_all::<ClientMessage>(&stream).unwrap(), messages);
    }

    #[test]
    fn empty_frame_is_the_default_envelope() {
        let decoded = decode_all::<ClientMessage>(&[0, 0, 0, 0]).unwrap();
        assert_eq!(decoded, vec![ClientMessage::default()]);
    }

    #[test]
    fn frame_of_exactly_max_size_passes_both_ways() {
        let message = server_message_of_size(MAX_FRAME_SIZE);
        let frame = encode_frame(&message).unwrap();
        assert_eq!(frame.len(), LENGTH_PREFIX_SIZE + MAX_FRAME_SIZE);
        let decoded = decode_all::<ServerMessage>(&frame).unwrap();
        assert_eq!(decoded, vec![message]);
    }

    #[test]
    fn encoding_one_byte_over_max_is_refused_and_writes_nothing() {
        let message = server_message_of_size(MAX_FRAME_SIZE + 1);
        let mut dst = BytesMut::new();
        let err = FrameEncoder::new().encode(&message, &mut dst).unwrap_err();
        assert!(
            matches!(err, WireError::FrameTooLarge { len, max } if len == MAX_FRAME_SIZE as u64 + 1 && max == MAX_FRAME_SIZE),
            "{err:?}"
        );
        assert!(dst.is_empty());
    }

    #[test]
    fn oversized_prefix_is_refused_without_reserving_the_payload() {
        for announced in [MAX_FRAME_SIZE as u32 + 1, u32::MAX] {
            let mut buf = BytesMut::with_capacity(64);
            buf.put_u32(announced);
            buf.put_slice(b"a few payload bytes");
            let mut decoder = FrameDecoder::<ClientMessage>::new();
            let err = decoder.decode(&mut buf).unwrap_err();
            assert!(
                matches!(err, WireError::FrameTooLarge { len, .. } if len == u64::from(announced)),
                "{err:?}"
            );
            assert!(
                buf.capacity() < 1024,
                "decoder reserved {} bytes for a refused frame",
                buf.capacity()
            );
            assert!(err.to_string().contains(&announced.to_string()), "{err}");
        }
    }

    #[test]
    fn max_size_prefix_waits_for_the_payload() {
        let mut buf = BytesMut::new();
        buf.put_u32(MAX_FRAME_SIZE as u32);
        let mut decoder = FrameDecoder::<ClientMessage>::new();
        assert!(decoder.decode(&mut buf).unwrap().is_none());
    }

    #[test]
    fn stream_ending_inside_a_frame_is_truncated() {
        let frame = encode_frame(&ClientMessage::move_(9, 0.0, 0.5)).unwrap();
        for cut in [1, 3, 4, 5, frame.len() - 1] {
            let err = decode_all::<ClientMessage>(&frame[..cut]).unwrap_err();
            assert!(
                matches!(err, WireError::Truncated { buffered } if buffered == cut),
                "cut at {cut}: {err:?}"
            );
            assert!(err.error_reply().is_none());
        }
    }

    #[test]
    fn garbage_payload_is_a_decode_error_with_a_reply() {
        // Field 1 declared as a length-delimited blob of 200 bytes inside a 3-byte frame.
        let garbage = [0, 0, 0, 3, 0x0a, 0xc8, 0x01];
        let err = decode_all::<ClientMessage>(&garbage).unwrap_err();
        assert!(matches!(err, WireError::Decode(_)), "{err:?}");
        let reply = err.error_reply().unwrap();
        match reply.payload {
            Some(pb::server_message::Payload::Error(e)) => {
                assert_eq!(e.seq, 0);
                assert!(e.message.starts_with("undecodable frame"), "{}", e.message);
            }
            other => panic!("expected an Error reply, got {other:?}"),
        }
    }

    #[test]
    fn wrong_wire_type_is_a_decode_error() {
        // seq (field 1) sent with wire type 5 (32-bit) instead of varint.
        let err = decode_all::<ClientMessage>(&[0, 0, 0, 5, 0x0d, 1, 2, 3, 4]).unwrap_err();
        assert!(matches!(err, WireError::Decode(_)), "{err:?}");
    }

    proptest! {
        #[test]
        fn arbitrary_bytes_never_panic_the_decoder(bytes in proptest::collection::vec(any::<u8>(), 0..256)) {
            let _ = decode_all::<ClientMessage>(&bytes);
        }

        #[test]
        fn move_commands_round_trip_at_any_split(
            seq in any::<u64>(), vx in -1.0f64..1.0, vy in -1.0f64..1.0, split in 0usize..64,
        ) {
            let message = ClientMessage::move_(seq, vx, vy);
            let frame = encode_frame(&message).unwrap();
            let split = split.min(frame.len());
            let mut decoder = FrameDecoder::<ClientMessage>::new();
            let mut buf = BytesMut::from(&frame[..split]);
            let early = decoder.decode(&mut buf).unwrap();
            let decoded = match early {
                Some(m) => m,
                None => {
                    buf.extend_from_slice(&frame[split..]);
                    decoder.decode(&mut buf).unwrap().unwrap()
                }
            };
            prop_assert_eq!(decoded, message);
        }
    }
}
