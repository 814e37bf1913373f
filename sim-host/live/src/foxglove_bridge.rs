//! The live streams on a Foxglove WebSocket server (the official `foxglove` crate, built
//! without its default features: no TLS, no C), for Foxglove's or Lichtblick's panels: Plot
//! (`/sandjumper/samples`, x axis `t_s`), State Transitions (`/sandjumper/state`), fault
//! status (`/sandjumper/fault`), and `/sandjumper/campaign`, `/sandjumper/events`.
//! Messages are JSON with a JSON Schema per channel.

use std::sync::Arc;

use foxglove::{
    ChannelBuilder, Context, RawChannel, Schema, WebSocketServer, WebSocketServerHandle,
};
use serde_json::json;

use super::bus::Event;
use super::foxglove_gate::{BROWSER_BLOCKED_PORTS, Gate, OriginPolicy};
use super::state::Update;
use crate::address::AllowedHosts;

/// A running Foxglove server and its channels.
pub struct FoxgloveBridge {
    /// The port it listens on (the gate's).
    pub port: u16,
    /// The Foxglove server's own loopback port, one of [`BROWSER_BLOCKED_PORTS`]: only the
    /// gate connects to it.
    pub server_port: u16,
    /// Stops accepting, and closes its relays, when the bridge goes (first).
    gate: Option<Gate>,
    /// Stopped with the bridge (a dropped handle leaves the server running).
    server: Option<WebSocketServerHandle>,
    /// The server and the channels hold it weakly: it lives as long as the bridge.
    _context: Arc<Context>,
    samples: Arc<RawChannel>,
    state: Arc<RawChannel>,
    fault: Arc<RawChannel>,
    campaign: Arc<RawChannel>,
    events: Arc<RawChannel>,
    channels: Vec<String>,
}

fn schema(name: &str, properties: serde_json::Value) -> Schema {
    let doc = json!({"type": "object", "properties": properties});
    Schema::new(name, "jsonschema", doc.to_string().into_bytes())
}

impl FoxgloveBridge {
    /// Start a server for samples named `channels`, reached at `addr` (port 0: any) through
    /// the [`Gate`] that checks each connection's `Host` and `Origin` (the `foxglove` crate's
    /// server checks neither, so it listens on a loopback port of its own); `page` is the live
    /// page's bound address, whose pages may connect. Must be called outside an async context.
    pub fn start(
        addr: std::net::SocketAddr,
        page: std::net::SocketAddr,
        channels: &[String],
    ) -> Result<Self, String> {
        let ctx = Context::new();
        // The channels first: a failure there leaves no server behind.
        let num = json!({"type": "number"});
        let text = json!({"type": "string"});
        let mut sample_props = serde_json::Map::new();
        sample_props.insert("t_s".into(), num.clone());
        for c in channels {
            sample_props.insert(c.clone(), num.clone());
        }
        let build = |topic: &str, s: Schema| {
            ChannelBuilder::new(topic)
                .context(&ctx)
                .message_encoding("json")
                .schema(s)
                .build_raw()
                .map_err(|e| format!("--foxglove: cannot open {topic} ({e})"))
        };
        let samples = build(
            "/sandjumper/samples",
            schema("sandjumper.Sample", serde_json::Value::Object(sample_props)),
        )?;
        let state = build(
            "/sandjumper/state",
            schema("sandjumper.State", json!({"t_s": num, "state": text})),
        )?;
        let fault = build(
            "/sandjumper/fault",
            schema("sandjumper.Fault", json!({"t_s": num, "fault": text})),
        )?;
        let campaign = build(
            "/sandjumper/campaign",
            schema("sandjumper.CampaignRecord", json!({"record": text})),
        )?;
        let events = build(
            "/sandjumper/events",
            schema("sandjumper.Event", json!({"kind": text})),
        )?;
        // The server on loopback, on a port browsers refuse to open: only the gate reaches
        // it from a web page's side.
        let mut started = None;
        for port in BROWSER_BLOCKED_PORTS {
            if let Ok(s) = WebSocketServer::new()
                .name("sandjumper")
                .bind("127.0.0.1", port)
                .context(&ctx)
                .start_blocking()
            {
                started = Some(s);
                break;
            }
        }
        let server = started.ok_or_else(|| {
            format!(
                "--foxglove {addr}: cannot start the Foxglove server: every loopback port \
                 browsers refuse to open is taken ({BROWSER_BLOCKED_PORTS:?}; other runs' \
                 servers hold them)"
            )
        })?;
        let inner = std::net::SocketAddr::from(([127, 0, 0, 1], server.port()));
        let gate = match Gate::start(addr, inner, |bound| OriginPolicy {
            hosts: AllowedHosts::for_bind(bound),
            page: AllowedHosts::for_bind(page),
        }) {
            Ok(g) => g,
            Err(e) => {
                drop(server.stop());
                return Err(e);
            }
        };
        Ok(Self {
            port: gate.addr.port(),
            server_port: inner.port(),
            gate: Some(gate),
            samples,
            state,
            fault,
            campaign,
            events,
            server: Some(server),
            _context: ctx.clone(),
            channels: channels.to_vec(),
        })
    }

    /// Publish what the page just received.
    pub fn publish(&self, updates: &[Update]) {
        for u in updates {
            match u {
                Update::Batch { batch, .. } => {
                    for (k, &t) in batch.t_s.iter().enumerate() {
                        let mut m = serde_json::Map::new();
                        m.insert("t_s".into(), json!(t));
                        for (c, name) in self.channels.iter().enumerate() {
                            let v = batch.columns.get(c).and_then(|col| col.get(k)).copied();
                            m.insert(name.clone(), json!(v.filter(|x| x.is_finite())));
                        }
                        self.samples
                            .log(serde_json::Value::Object(m).to_string().as_bytes());
                    }
                }
                Update::Event { event, .. } => {
                    let text = serde_json::to_string(event).unwrap_or_default();
                    self.events.log(text.as_bytes());
                    match event {
                        Event::State { t_s, state } => self
                            .state
                            .log(json!({"t_s": t_s, "state": state}).to_string().as_bytes()),
                        Event::Fault { t_s, fault } => self
                            .fault
                            .log(json!({"t_s": t_s, "fault": fault}).to_string().as_bytes()),
                        Event::Campaign(r) => self
                            .campaign
                            .log(serde_json::to_string(r).unwrap_or_default().as_bytes()),
                        _ => {}
                    }
                }
            }
        }
    }
}

impl Drop for FoxgloveBridge {
    fn drop(&mut self) {
        // The gate first (no new connection reaches the server), then the server: its
        // clients are closed at once (the shutdown handle dropped).
        drop(self.gate.take());
        if let Some(s) = self.server.take() {
            drop(s.stop());
        }
    }
}
