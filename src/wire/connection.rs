//! Typed connections: code above this layer speaks envelopes, never bytes.
//!
//! A [`Connection`] owns separate read and write halves so that a world can
//! [`split`](Connection::split) it and serve each client with a reader (commands
//! in) and a writer (states and errors out) running concurrently.

use futures::{SinkExt, StreamExt};
use prost::Message;
use tokio::io::{AsyncRead, AsyncWrite};
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};
use tokio::net::TcpStream;
use tokio_util::codec::{FramedRead, FramedWrite};

use super::codec::{FrameDecoder, FrameEncoder, WireError};
use super::pb;

/// The world's side of a client connection: reads commands, writes states.
pub type ServerConnection<R = OwnedReadHalf, W = OwnedWriteHalf> =
    Connection<pb::ClientMessage, pb::ServerMessage, R, W>;

/// A client's side: reads states, writes commands.
pub type ClientConnection<R = OwnedReadHalf, W = OwnedWriteHalf> =
    Connection<pb::ServerMessage, pb::ClientMessage, R, W>;

/// Reads envelopes of type `In`.
#[derive(Debug)]
pub struct FrameReader<In, R> {
    frames: FramedRead<R, FrameDecoder<In>>,
}

impl<In: Message + Default, R: AsyncRead + Unpin> FrameReader<In, R> {
    /// Frames read from `reader`.
    pub fn new(reader: R) -> Self {
        Self {
            frames: FramedRead::new(reader, FrameDecoder::new()),
        }
    }

    /// The next envelope; `Ok(None)` when the peer closed the connection
    /// cleanly between frames. After an error the reader is finished: the next
    /// call returns `Ok(None)`, because the byte stream can no longer be
    /// trusted to be aligned on frames.
    ///
    /// Cancel-safe: partial frames stay buffered in the reader, so `read` can
    /// be one branch of a `tokio::select!` loop.
    pub async fn read(&mut self) -> Result<Option<In>, WireError> {
        self.frames.next().await.transpose()
    }
}

/// Writes envelopes of type `Out`.
#[derive(Debug)]
pub struct FrameWriter<Out, W> {
    frames: FramedWrite<W, FrameEncoder<Out>>,
}

impl<Out: Message, W: AsyncWrite + Unpin> FrameWriter<Out, W> {
    /// Frames written to `writer`.
    pub fn new(writer: W) -> Self {
        Self {
            frames: FramedWrite::new(writer, FrameEncoder::new()),
        }
    }

    /// Writes and flushes one envelope. Not cancel-safe: if the future is
    /// dropped before the envelope was encoded it is not sent (once encoded it
    /// is sent whole with the next write or close).
    pub async fn write(&mut self, message: &Out) -> Result<(), WireError> {
        self.frames.send(message).await
    }

    /// Writes several envelopes and flushes once: a reader of the other end
    /// gets them in as few system calls (and wake-ups) as the socket allows.
    /// Not cancel-safe, like [`FrameWriter::write`].
    pub async fn write_all(&mut self, messages: &[Out]) -> Result<(), WireError> {
        for message in messages {
            self.frames.feed(message).await?;
        }
        SinkExt::<&Out>::flush(&mut self.frames).await
    }

    /// Flushes and shuts the write direction down (the peer sees end of stream).
    pub async fn close(&mut self) -> Result<(), WireError> {
        SinkExt::<&Out>::close(&mut self.frames).await
    }
}

/// A framed, typed, bidirectional connection.
#[derive(Debug)]
pub struct Connection<In, Out, R, W> {
    reader: FrameReader<In, R>,
    writer: FrameWriter<Out, W>,
}

impl<In: Message + Default, Out: Message> Connection<In, Out, OwnedReadHalf, OwnedWriteHalf> {
    /// Frames a TCP stream, with Nagle's algorithm off: messages are small
    /// and latency matters more than throughput.
    pub fn new(stream: TcpStream) -> Self {
        if let Err(err) = stream.set_nodelay(true) {
            tracing::debug!("cannot set TCP_NODELAY: {err}");
        }
        let (reader, writer) = stream.into_split();
        Self::from_parts(reader, writer)
    }
}

impl<In, Out, R, W> Connection<In, Out, R, W>
where
    In: Message + Default,
    Out: Message,
    R: AsyncRead + Unpin,
    W: AsyncWrite + Unpin,
{
    /// Frames any pair of byte halves (e.g. `tokio::io::split` of a duplex pipe in tests).
    pub fn from_parts(reader: R, writer: W) -> Self {
        Self {
            reader: FrameReader::new(reader),
            writer: FrameWriter::new(writer),
        }
    }

    /// See [`FrameReader::read`].
    pub async fn read(&mut self) -> Result<Option<In>, WireError> {
        self.reader.read().await
    }

    /// See [`FrameWriter::write`].
    pub async fn write(&mut self, message: &Out) -> Result<(), WireError> {
        self.writer.write(message).await
    }

    /// See [`FrameWriter::write_all`].
    pub async fn write_all(&mut self, messages: &[Out]) -> Result<(), WireError> {
        self.writer.write_all(messages).await
    }

    /// See [`FrameWriter::close`].
    pub async fn close(&mut self) -> Result<(), WireError> {
        self.writer.close().await
    }

    /// The halves, for reading and writing from different tasks.
    pub fn split(self) -> (FrameReader<In, R>, FrameWriter<Out, W>) {
        (self.reader, self.writer)
    }
}

#[cfg(test)]
mod tests {
    use tokio::io::AsyncWriteExt;

    use super::*;
    use crate::wire::pb::{ClientMessage, ServerMessage};

    #[tokio::test]
    async fn envelopes_cross_a_pipe_both_ways() {
        let (a, b) = tokio::io::duplex(1024);
        let (ar, aw) = tokio::io::split(a);
        let (br, bw) = tokio::io::split(b);
        let mut world: ServerConnection<_, _> = Connection::from_parts(ar, aw);
        let mut client: ClientConnection<_, _> = Connection::from_parts(br, bw);

        client.write(&ClientMessage::reset(1)).await.unwrap();
        client
            .write(&ClientMessage::move_(2, 0.0, 0.5))
            .await
            .unwrap();
        assert_eq!(world.read().await.unwrap(), Some(ClientMessage::reset(1)));
        assert_eq!(
            world.read().await.unwrap(),
            Some(ClientMessage::move_(2, 0.0, 0.5))
        );

        world
            .write(&ServerMessage::error(2, pb::error::Kind::Unspecified, "no"))
            .await
            .unwrap();
        assert_eq!(
            client.read().await.unwrap(),
            Some(ServerMessage::error(2, pb::error::Kind::Unspecified, "no"))
        );

        client.close().await.unwrap();
        assert_eq!(world.read().await.unwrap(), None);
    }

    #[tokio::test]
    async fn garbage_ends_the_reader_after_one_error() {
        let (mut raw, b) = tokio::io::duplex(1024);
        let (br, bw) = tokio::io::split(b);
        let mut world: ServerConnection<_, _> = Connection::from_parts(br, bw);
        raw.write_all(&[0, 0, 0, 2, 0xff, 0xff]).await.unwrap();
        raw.write_all(&crate::wire::encode_frame(&ClientMessage::reset(1)).unwrap())
            .await
            .unwrap();
        let err = world.read().await.unwrap_err();
        assert!(matches!(err, WireError::Decode(_)), "{err:?}");
        assert_eq!(world.read().await.unwrap(), None);
    }
}
