//! One time-ordered merge of a recording's sensor streams, in bounded memory.
//!
//! The idea of Cartographer's `OrderedMultiQueue` (`sensor/internal/ordered_multi_queue.h`):
//! each stream queues its messages and the merge releases them in stamp order, so that a
//! map built from several sensors does not depend on who delivered first. Real logs are
//! stored in receive order, not stamp order (a driver that stamps late, a bag chunk written
//! out of order), so a stream is not assumed sorted: each stream is a small heap, and a
//! message is released once the newest stamp seen on any stream is `window` past it — by
//! then every message of that instant has arrived unless it was delayed by more than the
//! window. One that still comes later than what was already released is *late*: counted
//! against its stream and dropped, never applied out of order. Memory holds at most the
//! messages of one window, whatever the length of the log.
//!
//! For each stream the merge records how far behind the newest stamp it ran (its lag when a
//! message was released without waiting for it), which names the stream that holds the
//! others up: a sensor whose clock runs behind, or one that arrives in bursts.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Counters of one stream of a merge.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct StreamStats {
    /// The stream's name (a topic).
    pub name: String,
    /// Messages pushed.
    pub pushed: u64,
    /// Messages released in order.
    pub released: u64,
    /// Messages arriving after a later-stamped message had already been released: dropped.
    pub late: u64,
    /// Messages that arrived after a later-stamped one of the same stream and were put
    /// back in order.
    pub reordered: u64,
    /// The largest gap, in key units, between this stream's newest key and the newest key
    /// of all streams at a release: how far this stream lagged behind the others.
    pub max_lag: i64,
    /// Messages that jumped far ahead of their stream and were not followed there: a glitched
    /// stamp, which does not move the merge's clock (it is still released, last).
    pub jumps: u64,
}

struct Queued<T> {
    key: i64,
    seq: u64,
    stream: usize,
    item: T,
}

impl<T> PartialEq for Queued<T> {
    fn eq(&self, o: &Self) -> bool {
        (self.key, self.seq) == (o.key, o.seq)
    }
}
impl<T> Eq for Queued<T> {}
impl<T> PartialOrd for Queued<T> {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl<T> Ord for Queued<T> {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        (self.key, self.seq).cmp(&(o.key, o.seq))
    }
}

/// What [`OrderedMerge::push`] did with a message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pushed {
    /// Queued; it will be released in order.
    Queued,
    /// Older than a message already released: dropped and counted.
    Late,
}

/// A time-ordered merge of several streams (see the module documentation).
///
/// Keys are integers (nanosecond stamps, or a file sequence number for data that must keep
/// file order); equal keys leave in push order.
pub struct OrderedMerge<T> {
    heap: BinaryHeap<Reverse<Queued<T>>>,
    window: i64,
    seq: u64,
    newest: Option<i64>,
    released: Option<i64>,
    newest_of: Vec<Option<i64>>,
    pending_jump: Vec<Option<i64>>,
    stats: Vec<StreamStats>,
    peak: usize,
}

impl<T> OrderedMerge<T> {
    /// A merge that waits `window` key units for late messages.
    pub fn new(window: i64) -> Self {
        Self {
            heap: BinaryHeap::new(),
            window: window.max(0),
            seq: 0,
            newest: None,
            released: None,
            newest_of: Vec::new(),
            pending_jump: Vec::new(),
            stats: Vec::new(),
            peak: 0,
        }
    }

    /// Registers a stream; returns its index.
    pub fn add_stream(&mut self, name: impl Into<String>) -> usize {
        self.stats.push(StreamStats { name: name.into(), ..Default::default() });
        self.newest_of.push(None);
        self.pending_jump.push(None);
        self.stats.len() - 1
    }

    /// Offers a message of `stream` with `key`.
    ///
    /// # Panics
    /// If `stream` was not returned by [`OrderedMerge::add_stream`] (a programming error).
    pub fn push(&mut self, stream: usize, key: i64, item: T) -> Pushed {
        let st = &mut self.stats[stream];
        st.pushed += 1;
        if self.released.is_some_and(|r| key < r) {
            st.late += 1;
            return Pushed::Late;
        }
        // A key far ahead of its stream moves the clock only once a second message confirms
        // the stream went there: one glitched stamp must not release everything at once
        // and make every later message of every stream late.
        let jump = self.window.saturating_mul(10).max(1);
        let advance = match self.newest_of[stream] {
            Some(n) if key < n => {
                st.reordered += 1;
                self.pending_jump[stream] = None;
                false
            }
            Some(n) if self.window > 0 && key.saturating_sub(n) > jump => match self.pending_jump[stream].take() {
                Some(_) => true,
                None => {
                    self.pending_jump[stream] = Some(key);
                    st.jumps += 1;
                    false
                }
            },
            _ => {
                self.pending_jump[stream] = None;
                true
            }
        };
        if advance {
            self.pending_jump[stream] = None;
            self.newest_of[stream] = Some(self.newest_of[stream].map_or(key, |n| n.max(key)));
            self.newest = Some(self.newest.map_or(key, |n| n.max(key)));
        }
        self.heap.push(Reverse(Queued { key, seq: self.seq, stream, item }));
        self.seq += 1;
        self.peak = self.peak.max(self.heap.len());
        Pushed::Queued
    }

    /// The next message that can be released now: `(stream, key, item)`.
    pub fn pop_ready(&mut self) -> Option<(usize, i64, T)> {
        let newest = self.newest?;
        let top = self.heap.peek()?;
        if newest.saturating_sub(top.0.key) < self.window {
            return None;
        }
        self.release(newest)
    }

    /// The next message once every stream has ended (drains in order).
    pub fn pop_final(&mut self) -> Option<(usize, i64, T)> {
        let newest = self.newest.unwrap_or(i64::MIN);
        self.release(newest)
    }

    fn release(&mut self, newest: i64) -> Option<(usize, i64, T)> {
        let Reverse(q) = self.heap.pop()?;
        for (s, n) in self.newest_of.iter().enumerate() {
            if let Some(n) = n {
                let lag = newest.saturating_sub(*n);
                self.stats[s].max_lag = self.stats[s].max_lag.max(lag);
            }
        }
        self.stats[q.stream].released += 1;
        self.released = Some(q.key);
        Some((q.stream, q.key, q.item))
    }

    /// Per-stream counters.
    pub fn stats(&self) -> &[StreamStats] {
        &self.stats
    }

    /// The most messages held at once.
    pub fn peak_queued(&self) -> usize {
        self.peak
    }

    /// The stream that lagged furthest behind the others, if any lagged at all.
    pub fn slowest_stream(&self) -> Option<&StreamStats> {
        self.stats.iter().filter(|s| s.max_lag > 0).max_by_key(|s| s.max_lag)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn drain(m: &mut OrderedMerge<u32>, out: &mut Vec<(usize, i64, u32)>) {
        while let Some(x) = m.pop_ready() {
            out.push(x);
        }
    }

    #[test]
    fn two_streams_interleave_in_key_order() {
        let mut m = OrderedMerge::new(10);
        let a = m.add_stream("a");
        let b = m.add_stream("b");
        let mut out = Vec::new();
        for (s, k) in [(a, 0), (a, 5), (b, 3), (a, 20), (b, 12), (a, 30), (b, 25)] {
            m.push(s, k, k as u32);
            drain(&mut m, &mut out);
        }
        while let Some(x) = m.pop_final() {
            out.push(x);
        }
        let keys: Vec<i64> = out.iter().map(|x| x.1).collect();
        assert_eq!(keys, vec![0, 3, 5, 12, 20, 25, 30]);
        assert_eq!(m.stats()[b].released, 3);
    }

    #[test]
    fn a_message_later_than_the_window_is_late_and_dropped() {
        let mut m = OrderedMerge::new(10);
        let a = m.add_stream("a");
        let mut out = Vec::new();
        for k in [0, 10, 20, 30] {
            m.push(a, k, 0);
            drain(&mut m, &mut out);
        }
        assert_eq!(out.len(), 3, "0, 10 and 20 are 10 behind the newest");
        assert_eq!(m.push(a, 5, 0), Pushed::Late);
        assert_eq!(m.push(a, 25, 0), Pushed::Queued);
        assert_eq!(m.stats()[a].late, 1);
        assert_eq!(m.stats()[a].reordered, 1);
    }

    #[test]
    fn one_glitched_stamp_does_not_make_the_rest_late() {
        let mut m = OrderedMerge::new(10);
        let a = m.add_stream("a");
        let b = m.add_stream("b");
        let mut out = Vec::new();
        for k in 0..100i64 {
            if k == 20 {
                m.push(a, 1_000_000, 0);
            }
            // b arrives slightly behind a, within the window.
            m.push(a, k * 5, 0);
            m.push(b, k * 5 - 3, 0);
            drain(&mut m, &mut out);
        }
        while let Some(x) = m.pop_final() {
            out.push(x);
        }
        assert_eq!(m.stats()[b].late, 0, "{:?}", m.stats());
        assert_eq!(m.stats()[a].late, 0);
        assert_eq!(m.stats()[a].jumps, 1);
        assert_eq!(out.len(), 201);
        assert_eq!(out.last().map(|x| x.1), Some(1_000_000), "the glitch is released last");
        // A real jump (the stream moved on) is followed after one confirming message.
        let mut m = OrderedMerge::new(10);
        let a = m.add_stream("a");
        let mut out = Vec::new();
        for k in [0, 5, 10, 1000, 1005, 1010, 1015, 1020, 1025] {
            m.push(a, k, 0);
            drain(&mut m, &mut out);
        }
        assert!(out.len() >= 6, "{out:?}");
    }

    #[test]
    fn memory_is_one_window_not_the_log() {
        let mut m = OrderedMerge::new(100);
        let a = m.add_stream("a");
        let mut out = Vec::new();
        for k in 0..100_000i64 {
            m.push(a, k * 10, 0);
            drain(&mut m, &mut out);
        }
        assert!(m.peak_queued() <= 11, "{}", m.peak_queued());
    }

    #[test]
    fn the_lagging_stream_is_named() {
        let mut m = OrderedMerge::new(5);
        let a = m.add_stream("fast");
        let b = m.add_stream("slow");
        let mut out = Vec::new();
        for k in 0..50 {
            m.push(a, k, 0);
            if k % 10 == 0 {
                m.push(b, k - 8, 0);
            }
            drain(&mut m, &mut out);
        }
        assert_eq!(m.slowest_stream().map(|s| s.name.as_str()), Some("slow"));
    }

    proptest! {
        /// Whatever the arrival order, what is released is in key order, and with a window
        /// as wide as the largest displacement nothing is late.
        #[test]
        fn releases_are_sorted(keys in proptest::collection::vec((0usize..3, 0i64..1000), 0..200)) {
            let mut m = OrderedMerge::new(1000);
            for s in 0..3 { m.add_stream(format!("{s}")); }
            let mut out = Vec::new();
            for (s, k) in &keys {
                prop_assert_eq!(m.push(*s, *k, 0), Pushed::Queued);
                drain(&mut m, &mut out);
            }
            while let Some(x) = m.pop_final() { out.push(x); }
            prop_assert_eq!(out.len(), keys.len());
            prop_assert!(out.windows(2).all(|w| w[0].1 <= w[1].1));
        }
    }
}
