//! The HTTP server of the live view: `/` the page (chart library embedded: nothing is fetched
//! from the internet), `/state.json` everything the page knows, `/events` Server-Sent Events
//! of what is new. It runs on a thread of its own with its own runtime, so nothing it does
//! (a slow browser, many tabs) reaches the run: the run only ever writes into the bus.

use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use axum::Router;
use axum::extract::State;
use axum::http::header;
use axum::response::sse::{Event as SseEvent, KeepAlive, Sse};
use axum::response::{Html, IntoResponse};
use axum::routing::get;
use futures_util::stream::{self, Stream};
use tokio::sync::broadcast;

use super::bus::LiveFeed;
use super::state::{LiveState, Update};

const PAGE: &str = include_str!("assets/page.html");
const UPLOT_JS: &str = include_str!("assets/uPlot.iife.min.js");
const UPLOT_CSS: &str = include_str!("assets/uPlot.min.css");

/// How often the bus is read, ms.
const PUMP_MS: u64 = 25;

#[derive(Clone)]
struct Shared {
    /// The `Host` names this server answers.
    allowed: crate::address::AllowedHosts,
    state: Arc<Mutex<LiveState>>,
    updates: broadcast::Sender<String>,
    #[cfg(feature = "foxglove")]
    foxglove: Option<Arc<super::foxglove_bridge::FoxgloveBridge>>,
}

/// A running live view.
pub struct LiveServer {
    /// The address it listens on (the port chosen when 0 was asked for).
    pub addr: SocketAddr,
    /// The page's address for the user (the machine's name for a bind to every interface).
    url: String,
    /// The Foxglove WebSocket server's port, if one runs.
    pub foxglove_port: Option<u16>,
    state: Arc<Mutex<LiveState>>,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl LiveServer {
    /// The page's address.
    pub fn url(&self) -> String {
        self.url.clone()
    }

    /// A copy of what the page shows now (after the bus's latest was read).
    pub fn snapshot(&self) -> LiveState {
        match self.state.lock() {
            Ok(s) => s.clone(),
            Err(p) => p.into_inner().clone(),
        }
    }
}

impl Drop for LiveServer {
    fn drop(&mut self) {
        if let Some(s) = self.stop.take() {
            let _ = s.send(());
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Serve `feed` at `addr` on this machine only ([`crate::address::parse_listen`]'s forms: a
/// bare PORT on 127.0.0.1, `localhost:PORT`, a loopback `IP:PORT`; port 0: any free port).
/// Fails (a message saying what and where) if the address cannot be bound or is beyond this
/// machine.
pub fn serve(addr: &str, feed: LiveFeed) -> Result<LiveServer, String> {
    serve_with_foxglove(addr, feed, None, false)
}

/// Whether this build can serve the streams to Foxglove (`--features foxglove`).
pub const FOXGLOVE: bool = cfg!(feature = "foxglove");

/// [`serve`], and the same streams on a Foxglove WebSocket server at `foxglove` (the same
/// address forms, behind a gate that checks `Host` and `Origin`), when given (this build must
/// have the `foxglove` feature). `public`: the user asked for an address beyond this machine
/// (`--live-public`); without it such an address is refused. Requests whose `Host` is not this server's own name are refused (403).
pub fn serve_with_foxglove(
    addr: &str,
    feed: LiveFeed,
    foxglove: Option<&str>,
    public: bool,
) -> Result<LiveServer, String> {
    // A bare port binds the loopback interface (the page has no login).
    let sock = crate::address::parse_listen("--live", addr)?;
    crate::address::check_exposure("--live", addr, sock, public)?;
    let foxglove_sock = foxglove
        .map(|a| {
            let s = crate::address::parse_listen("--foxglove", a)?;
            crate::address::check_exposure("--foxglove", a, s, public).map(|()| s)
        })
        .transpose()?;
    let std_listener = std::net::TcpListener::bind(sock)
        .map_err(|e| format!("--live {addr}: cannot listen there ({e})"))?;
    std_listener
        .set_nonblocking(true)
        .map_err(|e| format!("--live {addr}: {e}"))?;
    let local = std_listener
        .local_addr()
        .map_err(|e| format!("--live {addr}: {e}"))?;
    let state = Arc::new(Mutex::new(LiveState::new(&feed)));
    let (updates, _) = broadcast::channel(4096);
    #[cfg(feature = "foxglove")]
    let bridge = foxglove_sock
        .map(|a| {
            super::foxglove_bridge::FoxgloveBridge::start(a, local, &feed.channels).map(Arc::new)
        })
        .transpose()?;
    #[cfg(not(feature = "foxglove"))]
    let _ = foxglove_sock;
    #[cfg(not(feature = "foxglove"))]
    if let Some(a) = foxglove {
        return Err(format!(
            "--foxglove {a}: this build has no Foxglove server (build sandjumper-cli with `--features foxglove`)"
        ));
    }
    let foxglove_port = {
        #[cfg(feature = "foxglove")]
        {
            bridge.as_ref().map(|b| b.port)
        }
        #[cfg(not(feature = "foxglove"))]
        {
            None
        }
    };
    let allowed = crate::address::AllowedHosts::for_bind(local);
    let url = allowed.url(local);
    let shared = Shared {
        allowed,
        state: state.clone(),
        updates,
        #[cfg(feature = "foxglove")]
        foxglove: bridge,
    };
    let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
    let thread = std::thread::Builder::new()
        .name("live-view".into())
        .spawn(move || {
            let Ok(rt) = tokio::runtime::Builder::new_current_thread()
                .enable_all()
                .build()
            else {
                return;
            };
            rt.block_on(async move {
                let Ok(listener) = tokio::net::TcpListener::from_std(std_listener) else {
                    return;
                };
                let app = Router::new()
                    .route("/", get(page))
                    .route("/uPlot.js", get(uplot_js))
                    .route("/uPlot.css", get(uplot_css))
                    .route("/state.json", get(state_json))
                    .route("/events", get(events))
                    .layer(axum::middleware::from_fn_with_state(
                        shared.clone(),
                        own_host_only,
                    ))
                    .with_state(shared.clone());
                let pump = {
                    let shared = shared.clone();
                    async move {
                        let mut tick = tokio::time::interval(Duration::from_millis(PUMP_MS));
                        loop {
                            tick.tick().await;
                            pump_once(&shared, &feed);
                        }
                    }
                };
                // Not a graceful shutdown: an open event stream never ends by itself, and the
                // command must end when the user says so. Leaving the runtime drops every
                // connection.
                let server = axum::serve(listener, app);
                tokio::select! {
                    _ = server => {},
                    () = pump => {},
                    _ = stop_rx => {},
                }
            });
        })
        .map_err(|e| format!("cannot start the live view's thread: {e}"))?;
    Ok(LiveServer {
        url,
        addr: local,
        foxglove_port,
        state,
        stop: Some(stop_tx),
        thread: Some(thread),
    })
}

/// Read the bus into the state and broadcast what is new.
fn pump_once(shared: &Shared, feed: &LiveFeed) {
    let updates: Vec<Update> = match shared.state.lock() {
        Ok(mut s) => s.absorb(feed),
        Err(p) => p.into_inner().absorb(feed),
    };
    #[cfg(feature = "foxglove")]
    if let Some(b) = &shared.foxglove {
        b.publish(&updates);
    }
    for u in updates {
        if let Ok(text) = serde_json::to_string(&u) {
            // No subscriber is no error: the state keeps it for the next page load.
            let _ = shared.updates.send(text);
        }
    }
}

/// Refuse (403) a request whose `Host` is not this server's own name: a page of another site
/// whose name was rebound to this machine's address (DNS rebinding) gets nothing.
async fn own_host_only(
    State(shared): State<Shared>,
    request: axum::extract::Request,
    next: axum::middleware::Next,
) -> axum::response::Response {
    let host = request
        .headers()
        .get(header::HOST)
        .and_then(|h| h.to_str().ok())
        .unwrap_or("");
    if shared.allowed.allows(host) {
        next.run(request).await
    } else {
        (
            axum::http::StatusCode::FORBIDDEN,
            [(header::CONTENT_TYPE, "text/plain")],
            format!(
                "403: this live view answers its own address only, not Host `{host}` (open the \
                 URL the command printed)\n"
            ),
        )
            .into_response()
    }
}

async fn page() -> Html<&'static str> {
    Html(PAGE)
}

async fn uplot_js() -> impl IntoResponse {
    ([(header::CONTENT_TYPE, "text/javascript")], UPLOT_JS)
}

async fn uplot_css() -> impl IntoResponse {
    ([(header::CONTENT_TYPE, "text/css")], UPLOT_CSS)
}

async fn state_json(State(shared): State<Shared>) -> impl IntoResponse {
    // A copy taken under the lock (memory copies), serialised after it is released: a page
    // load never holds the pump (and the run's view of the bus) for the JSON of the window.
    let copy = match shared.state.lock() {
        Ok(s) => s.clone(),
        Err(p) => p.into_inner().clone(),
    };
    let text = serde_json::to_string(&copy).unwrap_or_else(|e| format!("{{\"error\":\"{e}\"}}"));
    (
        [
            (header::CONTENT_TYPE, "application/json"),
            (header::CACHE_CONTROL, "no-store"),
        ],
        text,
    )
}

/// The stream of updates; a client too slow for the broadcast buffer is told to reload
/// `state.json` (`resync`) rather than silently missing updates.
async fn events(
    State(shared): State<Shared>,
) -> Sse<impl Stream<Item = Result<SseEvent, std::convert::Infallible>>> {
    let rx = shared.updates.subscribe();
    let s = stream::unfold(rx, |mut rx| async move {
        let ev = match rx.recv().await {
            Ok(text) => SseEvent::default().event("update").data(text),
            Err(broadcast::error::RecvError::Lagged(n)) => {
                SseEvent::default().event("resync").data(n.to_string())
            }
            Err(broadcast::error::RecvError::Closed) => return None,
        };
        Some((Ok(ev), rx))
    });
    Sse::new(s).keep_alive(KeepAlive::default())
}
