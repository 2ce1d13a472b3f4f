//! Graceful shutdown that cannot be broken: a cloneable signal the server
//! and every design actor watch so they stop accepting work and flush their
//! state to the store, and the OS signal watcher of the binary
//! ([`watch_os_signals`]): the first SIGTERM or Ctrl-C triggers the graceful
//! shutdown and arms a deadline after which the process exits whatever state
//! it is in; a second signal exits at once.

use tokio::sync::watch;

/// A one-shot, cloneable "shut down now" signal.
#[derive(Clone, Debug)]
pub struct Shutdown {
    tx: watch::Sender<bool>,
}

impl Default for Shutdown {
    fn default() -> Self {
        Self::new()
    }
}

impl Shutdown {
    /// A signal not yet triggered.
    pub fn new() -> Self {
        Self {
            tx: watch::channel(false).0,
        }
    }

    /// Triggers the shutdown (idempotent).
    pub fn trigger(&self) {
        self.tx.send_replace(true);
    }

    /// Whether the shutdown was triggered.
    pub fn is_triggered(&self) -> bool {
        *self.tx.borrow()
    }

    /// Resolves once the shutdown is triggered.
    pub async fn wait(&self) {
        let mut rx = self.tx.subscribe();
        // An error means the sender is gone, which cannot happen while
        // `self` holds it; either way, shutting down is right.
        let _ = rx.wait_for(|&v| v).await;
    }
}

/// How the process ended when the signal watcher had to end it.
pub const FORCED_EXIT_CODE: i32 = 1;

/// Watches SIGTERM and Ctrl-C on a thread of its own (with its own small
/// runtime, so a busy or wedged server runtime cannot delay it). The first
/// signal triggers `shutdown`; if the process is still running `deadline`
/// later, or on a second signal, `before_exit` runs (flush the logs, briefly)
/// and the process exits with [`FORCED_EXIT_CODE`].
pub fn watch_os_signals(
    shutdown: Shutdown,
    deadline: std::time::Duration,
    before_exit: impl Fn() + Send + 'static,
) -> std::io::Result<()> {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?;
    // Listen before returning, so a signal sent right after the banner is
    // never met by the default action.
    let mut signals = {
        let _rt = rt.enter();
        OsSignals::new()
    };
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            rt.block_on(async move {
                signals.next().await;
                // Trigger first: the log line after it may go nowhere.
                shutdown.trigger();
                tracing::info!("shutting down (a second signal exits at once)");
                tokio::select! {
                    _ = signals.next() => {
                        tracing::warn!("second signal: exiting now");
                    }
                    _ = tokio::time::sleep(deadline) => {
                        tracing::error!(?deadline, "shutdown not finished in time: exiting now");
                    }
                }
                before_exit();
                std::process::exit(FORCED_EXIT_CODE);
            })
        })?;
    Ok(())
}

/// SIGTERM and SIGINT as one stream.
struct OsSignals {
    #[cfg(unix)]
    term: Option<tokio::signal::unix::Signal>,
    #[cfg(unix)]
    int: Option<tokio::signal::unix::Signal>,
}

#[cfg(unix)]
async fn recv(s: &mut Option<tokio::signal::unix::Signal>) {
    match s {
        Some(s) => {
            s.recv().await;
        }
        None => std::future::pending::<()>().await,
    }
}

impl OsSignals {
    fn new() -> Self {
        #[cfg(unix)]
        {
            use tokio::signal::unix::{SignalKind, signal};
            let open = |k: SignalKind, name: &str| match signal(k) {
                Ok(s) => Some(s),
                Err(e) => {
                    tracing::error!("cannot listen for {name}: {e}");
                    None
                }
            };
            Self {
                term: open(SignalKind::terminate(), "SIGTERM"),
                int: open(SignalKind::interrupt(), "SIGINT"),
            }
        }
        #[cfg(not(unix))]
        Self {}
    }

    /// The next SIGTERM or SIGINT.
    async fn next(&mut self) {
        #[cfg(unix)]
        tokio::select! {
            _ = recv(&mut self.term) => tracing::info!("SIGTERM received"),
            _ = recv(&mut self.int) => tracing::info!("Ctrl-C received"),
        }
        #[cfg(not(unix))]
        {
            let _ = tokio::signal::ctrl_c().await;
        }
    }
}
