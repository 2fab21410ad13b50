//! How Rerun batches what weft logs into chunks: for a file, large chunks;
//! for the window, one frame's drawing at a time.

use std::time::Duration;

/// How Rerun batches a recording written to a file (or a pipe): into
/// chunks flushed every 200 ms (Rerun's default tick), not every 2 MiB.
///
/// A full frame of a 64 × 64 sheet is about 930 kB, so with Rerun's default
/// of 2 MiB each entity's chunk held two frames, and encoding, compressing
/// and indexing that many small chunks took about 12 % of a full step
/// (BENCHMARKS.md, "Measured design choices"). Live streams keep
/// Rerun's low-latency batching. The `RERUN_FLUSH_*` environment variables
/// still apply on top.
pub fn file_batching() -> Result<rerun::log::ChunkBatcherConfig, rerun::log::ChunkBatcherError> {
    rerun::log::ChunkBatcherConfig {
        flush_num_bytes: FILE_CHUNK_BYTES,
        ..rerun::log::ChunkBatcherConfig::DEFAULT
    }
    .apply_env()
}

/// The batching of a stream to the window: chunks are sent when
/// [`Telemetry::log_frame`](super::Telemetry::log_frame) has logged a frame's drawing
/// ([`Telemetry::send`](super::Telemetry::send)), and otherwise once a second, so
/// that the viewer never receives part of a frame's drawing.
pub fn whole_frames() -> rerun::log::ChunkBatcherConfig {
    rerun::log::ChunkBatcherConfig {
        flush_tick: Duration::from_secs(1),
        flush_num_bytes: u64::MAX,
        ..rerun::log::ChunkBatcherConfig::DEFAULT
    }
}

/// The pending bytes that flush a file recording's chunks before the tick
/// does: above what 200 ms of full frames of a 128 × 128 sheet hold.
const FILE_CHUNK_BYTES: u64 = 32 << 20;
