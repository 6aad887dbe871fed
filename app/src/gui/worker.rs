//! A job on a worker thread of the app (the sweep, the trade-off): it sends its results one by one as they
//! complete, is cancelled on request (it checks between results) or when dropped, and says whether it
//! finished or why it failed. The UI polls it once per frame; nothing waits.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, Receiver};
use std::sync::Arc;
use std::thread::JoinHandle;

use anyhow::Result;

enum Message<T> {
    Item(T),
    Done,
    Failed(String),
}

/// A running or finished job whose results are `T`s.
pub struct Worker<T> {
    pub finished: bool,
    pub error: Option<String>,
    cancel: Arc<AtomicBool>,
    receiver: Receiver<Message<T>>,
    thread: Option<JoinHandle<()>>,
}

impl<T: Send + 'static> Worker<T> {
    /// Run `work` on a thread: it sends each result through its second argument and stops early when its
    /// first (the cancel flag) is set.
    pub fn start(work: impl FnOnce(&AtomicBool, &dyn Fn(T)) -> Result<()> + Send + 'static) -> Worker<T> {
        let (tx, rx) = channel();
        let cancel = Arc::new(AtomicBool::new(false));
        let flag = cancel.clone();
        let thread = std::thread::spawn(move || {
            let send = |item| {
                let _ = tx.send(Message::Item(item));
            };
            let end = match work(&flag, &send) {
                Ok(()) => Message::Done,
                Err(e) => Message::Failed(format!("{e:#}")),
            };
            let _ = tx.send(end);
        });
        Worker { finished: false, error: None, cancel, receiver: rx, thread: Some(thread) }
    }

    /// The results sent since the last poll; the thread is joined once it has finished.
    pub fn poll(&mut self) -> Vec<T> {
        let mut items = Vec::new();
        while let Ok(m) = self.receiver.try_recv() {
            match m {
                Message::Item(item) => items.push(item),
                Message::Done => self.finished = true,
                Message::Failed(e) => {
                    self.error = Some(e);
                    self.finished = true;
                }
            }
        }
        if self.finished {
            if let Some(t) = self.thread.take() {
                let _ = t.join();
            }
        }
        items
    }

    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
}

impl<T> Drop for Worker<T> {
    fn drop(&mut self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
}
