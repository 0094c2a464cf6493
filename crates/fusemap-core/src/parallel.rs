//! Fork–join for the scan matcher, the map set and the camera calibration's cost curves (rayon's work-stealing `join` and
//! indexed parallel iterators with the `parallel` feature, the same calls one after the
//! other without it).
//!
//! Only work whose result does not depend on how it is split goes through here: halves of
//! an argmax whose ties are broken by order, independent cost evaluations collected in a
//! fixed order, maps that share no cell. So a run's poses and maps are the same to the
//! bit on one thread or many.

/// Runs `a` and `b`, in parallel when the `parallel` feature is on.
#[inline]
pub fn join<A, B, RA, RB>(a: A, b: B) -> (RA, RB)
where
    A: FnOnce() -> RA + Send,
    B: FnOnce() -> RB + Send,
    RA: Send,
    RB: Send,
{
    #[cfg(feature = "parallel")]
    {
        rayon::join(a, b)
    }
    #[cfg(not(feature = "parallel"))]
    {
        (a(), b())
    }
}

/// Runs `f` on a worker of the thread pool, so that the [`join`]s inside it hand work to
/// the other worker through its local queue; a `join` called from outside the pool
/// instead sends both halves there and sleeps until they are done, which costs more than
/// a small match saves. The caller's thread waits; results are those of `f()`.
#[inline]
pub fn on_worker<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    #[cfg(feature = "parallel")]
    {
        rayon::scope(|_| f())
    }
    #[cfg(not(feature = "parallel"))]
    {
        f()
    }
}

/// Makes the calling thread a worker of the global thread pool (call it first thing in
/// `main`), so the matcher's joins from it are pushes onto its own queue rather than
/// hand-offs to the pool and back. Without the `parallel` feature, or when the pool was
/// already set up, it does nothing: the results are the same either way.
pub fn adopt_calling_thread() {
    #[cfg(feature = "parallel")]
    {
        let _ = rayon::ThreadPoolBuilder::new().use_current_thread().build_global();
    }
}

/// The threads of the pool (1 without the `parallel` feature): with one, work that could
/// run beside the caller runs where its result is needed instead.
pub fn threads() -> usize {
    #[cfg(feature = "parallel")]
    {
        rayon::current_num_threads()
    }
    #[cfg(not(feature = "parallel"))]
    {
        1
    }
}

/// `items.iter().map(f)` collected in order, the items spread over every thread of the
/// pool (rayon's indexed parallel iterator keeps the order whatever the split). Each item
/// is a task of its own: the items are few and of very unequal cost (searches, grids), and
/// a thread that finishes early takes the next one rather than waiting on a half.
pub fn map_all<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync + Send) -> Vec<R> {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        items.par_iter().with_max_len(1).map(f).collect()
    }
    #[cfg(not(feature = "parallel"))]
    {
        items.iter().map(f).collect()
    }
}

/// `items.iter_mut().map(f)` collected in order, each item a task of its own as in
/// [`map_all`]: for a few heavy, independent items that `f` changes (the maps of one
/// pass, each updated by one thread, so each ends as it would on one thread).
pub fn map_all_mut<T: Send, R: Send>(items: &mut [T], f: impl Fn(&mut T) -> R + Sync + Send) -> Vec<R> {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        items.par_iter_mut().with_max_len(1).map(f).collect()
    }
    #[cfg(not(feature = "parallel"))]
    {
        items.iter_mut().map(f).collect()
    }
}

/// `items.iter().map(f)` collected in order, the two halves computed by [`join`].
pub fn map_halves<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let (left, right) = items.split_at(items.len() / 2);
    let (mut a, b) = join(|| left.iter().map(&f).collect::<Vec<R>>(), || right.iter().map(&f).collect::<Vec<R>>());
    a.extend(b);
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halves_keep_the_order() {
        let v: Vec<u32> = (0..11).collect();
        assert_eq!(map_halves(&v, |x| x * 2), (0..11).map(|x| x * 2).collect::<Vec<_>>());
        assert!(map_halves(&[] as &[u32], |x| *x).is_empty());
        assert_eq!(join(|| 1, || "b"), (1, "b"));
        assert_eq!(on_worker(|| join(|| 2, || 3)), (2, 3));
        assert_eq!(map_all(&v, |x| x + 1), (1..12).collect::<Vec<_>>());
        let mut w = v.clone();
        assert_eq!(map_all_mut(&mut w, |x| std::mem::replace(x, 0) * 3), (0..11).map(|x| x * 3).collect::<Vec<_>>());
        assert!(w.iter().all(|&x| x == 0));
    }
}
