//! Work split across threads: each item on a thread of its own, the first on the calling
//! thread, and on the calling thread too any item whose thread the system refuses.

use std::sync::Mutex;

/// `f` of each item of `work`, in order: the first on this thread, each other on a thread
/// of its own (or, if the system refuses that thread, on this one after the first).
///
/// # Panics
/// If `f` panics on any thread: with `f`'s panic.
pub(crate) fn on_threads<W: Send, R: Send>(work: Vec<W>, f: impl Fn(W) -> R + Sync) -> Vec<R> {
    // Each item taken by whichever thread does it.
    let items: Vec<Mutex<Option<W>>> = work.into_iter().map(|w| Mutex::new(Some(w))).collect();
    let run = |k: usize| {
        let item = items.get(k)?.lock().ok().and_then(|mut w| w.take());
        item.map(&f)
    };
    let run = &run;
    std::thread::scope(|scope| {
        let threads: Vec<_> = (1..items.len())
            .map(|k| {
                (
                    k,
                    std::thread::Builder::new().spawn_scoped(scope, move || run(k)),
                )
            })
            .collect();
        let mut out: Vec<R> = run(0).into_iter().collect();
        for (k, thread) in threads {
            let done = match thread {
                Ok(t) => t.join().unwrap_or_else(|p| std::panic::resume_unwind(p)),
                // A thread the system refused: its item is done here.
                Err(_) => run(k),
            };
            out.extend(done);
        }
        out
    })
}

#[cfg(test)]
mod tests {
    use super::on_threads;

    #[test]
    fn every_item_is_done_once_and_the_results_are_in_order() {
        for n in [0, 1, 2, 7] {
            let seen = std::sync::Mutex::new(Vec::new());
            let out = on_threads((0..n).collect(), |k: usize| {
                seen.lock().unwrap().push(k);
                k * 10
            });
            assert_eq!(out, (0..n).map(|k| k * 10).collect::<Vec<_>>());
            let mut seen = seen.into_inner().unwrap();
            seen.sort_unstable();
            assert_eq!(seen, (0..n).collect::<Vec<_>>());
        }
    }
}
