//! Response bodies sent as they are made, through a channel of a few
//! pieces: a client that reads slowly holds those pieces, not the whole
//! response (300 unread 5.9 MB steps, each held whole, held 1.7 GB). The
//! maker waits while the channel is full and stops when the client goes.

use std::io::{self, Write};

use axum::body::{Body, Bytes};
use tokio::sync::mpsc;

/// The size of a piece (the smallest, for a step's parts read from the
/// database). A response to a client that has stopped reading holds three:
/// one the connection is writing, one in the channel, one made and waiting
/// (besides what the sockets buffer).
pub const PIECE: usize = 512 * 1024;

/// Pieces made but not yet taken by the connection.
const IN_FLIGHT: usize = 1;

/// Where a response's maker sends its pieces; an error ends the response
/// short, and the connection closes.
pub type Pieces = mpsc::Sender<io::Result<Bytes>>;

/// A body, and the sender its pieces come from.
pub fn channel() -> (Pieces, Body) {
    let (pieces, received) = mpsc::channel(IN_FLIGHT);
    let body = Body::from_stream(futures_util::stream::unfold(
        received,
        |mut received| async move { received.recv().await.map(|piece| (piece, received)) },
    ));
    (pieces, body)
}

/// A writer for blocking code (the archive's zip): it sends what it is
/// given a piece at a time, waiting while the channel is full, and fails
/// once the client has gone.
pub struct PieceWriter {
    pieces: Pieces,
    piece: Vec<u8>,
}

impl PieceWriter {
    pub fn new(pieces: Pieces) -> Self {
        Self {
            pieces,
            piece: Vec::with_capacity(PIECE),
        }
    }

    fn send(&mut self) -> io::Result<()> {
        if self.piece.is_empty() {
            return Ok(());
        }
        let piece = std::mem::replace(&mut self.piece, Vec::with_capacity(PIECE));
        self.pieces
            .blocking_send(Ok(Bytes::from(piece)))
            .map_err(|_| io::Error::new(io::ErrorKind::BrokenPipe, "the client went away"))
    }
}

impl Write for PieceWriter {
    fn write(&mut self, bytes: &[u8]) -> io::Result<usize> {
        let taken = bytes.len().min(PIECE - self.piece.len());
        self.piece.extend_from_slice(&bytes[..taken]);
        if self.piece.len() == PIECE {
            self.send()?;
        }
        Ok(taken)
    }

    /// Sends what is held: the last piece, once the writing is done.
    fn flush(&mut self) -> io::Result<()> {
        self.send()
    }
}

/// Sends `bytes`, already made whole, a piece at a time: the connection
/// copies no more than a piece ahead of the client.
pub async fn send_whole(pieces: &Pieces, bytes: Bytes) -> Result<(), ClientGone> {
    let mut at = 0;
    while at < bytes.len() {
        let end = (at + PIECE).min(bytes.len());
        pieces
            .send(Ok(bytes.slice(at..end)))
            .await
            .map_err(|_| ClientGone)?;
        at = end;
    }
    Ok(())
}

/// The client closed its connection, or the server gave up on it: the
/// rest of the response has nowhere to go.
#[derive(Debug)]
pub struct ClientGone;

#[cfg(test)]
mod tests {
    use super::*;
    use futures_util::StreamExt;

    #[tokio::test]
    async fn a_writer_sends_what_it_is_given_in_pieces_and_the_rest_on_flush() {
        let (pieces, body) = channel();
        let written: Vec<u8> = (0..PIECE * 2 + 10).map(|i| (i % 251) as u8).collect();
        let expected = written.clone();
        let maker = tokio::task::spawn_blocking(move || {
            let mut writer = PieceWriter::new(pieces);
            writer.write_all(&written).unwrap();
            writer.flush().unwrap();
        });
        let mut body = body.into_data_stream();
        let mut sizes = Vec::new();
        let mut received = Vec::new();
        while let Some(data) = body.next().await {
            let data = data.unwrap();
            sizes.push(data.len());
            received.extend_from_slice(&data);
        }
        maker.await.unwrap();
        assert_eq!(sizes, [PIECE, PIECE, 10]);
        assert_eq!(received, expected);
    }

    #[tokio::test]
    async fn a_writer_fails_once_the_body_is_dropped() {
        let (pieces, body) = channel();
        drop(body);
        let failed = tokio::task::spawn_blocking(move || {
            let mut writer = PieceWriter::new(pieces);
            writer.write_all(&vec![0; PIECE]).unwrap_err().kind()
        });
        assert_eq!(failed.await.unwrap(), io::ErrorKind::BrokenPipe);
    }
}
