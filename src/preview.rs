//! The live preview of `mcrt render --preview [ADDR]`: a small HTTP server (`tiny_http`) that
//! shows the image as it converges.
//!
//! The render never waits for it and it never touches the film: after each progressive pass
//! the render [`Preview::publish`]es a snapshot (the film's mean image, as written to the
//! output, with the samples done, the time and the noise estimate), and the server answers
//! from the latest snapshot on its own thread. The rendered bits are therefore the same with
//! or without a preview.
//!
//! Routes (all GET, except `/stop`):
//! - `/`: the page (`preview.html`), which polls `/status.json` and reloads the image after
//!   each pass, with exposure and tone-map controls and a stop button;
//! - `/status.json`: `{"state", "pass", "spp", "spp_max", "spp_mean", "spp_target",
//!   "elapsed", "noise", "width", "height"}`;
//! - `/image.png?exposure=EV&tonemap=clamp|reinhard|aces`: the snapshot as 8-bit sRGB, through
//!   the same conversion as a PNG output ([`crate::image::encode_png`]);
//! - `/image.exr`: the snapshot as linear 32-bit float OpenEXR;
//! - `POST /stop`: sets the render's cancel flag, as the first SIGINT does (the render ends
//!   after the current tile and writes its image and checkpoint). It is the only control.
//!
//! Only loopback is bound unless an address is given. Requests whose `Host` is a name other
//! than `localhost` (DNS rebinding) and a `/stop` whose `Origin` is another site (a form
//! posted by some other page) are refused with 403.

use crate::film::Film;
use crate::image::{encode_exr, encode_png, Image, ToneMap, WriteOptions};
use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use tiny_http::{Header, Method, Request, Response, Server};

/// The page, served at `/`.
const PAGE: &str = include_str!("preview.html");

/// The longest progressive pass while a preview is served, so that the page updates at least
/// this often (passes otherwise double in length).
pub const MAX_PASS: Duration = Duration::from_secs(1);

/// The exposure range the PNG route accepts, in stops.
const MAX_EXPOSURE: f32 = 32.0;

/// The render's state as the page shows it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum State {
    /// Loading the scene and building the acceleration structure.
    Loading,
    Rendering,
    /// The stop button was pressed; the current tile is finishing.
    Stopping,
    /// The render ended; the output is being written.
    Done,
}

impl State {
    fn name(self) -> &'static str {
        match self {
            State::Loading => "loading",
            State::Rendering => "rendering",
            State::Stopping => "stopping",
            State::Done => "done",
        }
    }
}

/// What the server shows: the latest published pass.
#[derive(Clone, Debug)]
struct Snapshot {
    state: State,
    pass: u32,
    image: Option<Arc<Image>>,
    spp: u32,
    spp_max: u32,
    spp_mean: f64,
    spp_target: Option<u32>,
    elapsed: Duration,
    noise: Option<f64>,
}

struct Shared {
    snapshot: Mutex<Snapshot>,
    cancel: &'static AtomicBool,
    start: Instant,
}

/// A running preview server; dropping it stops the server.
pub struct Preview {
    server: Arc<Server>,
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
    addr: SocketAddr,
}

impl Preview {
    /// Binds `addr` (e.g. `127.0.0.1:0` for any free port) and starts serving. `cancel` is the
    /// flag the stop button sets.
    pub fn start(addr: &str, cancel: &'static AtomicBool) -> Result<Preview, String> {
        let sock: SocketAddr = addr.parse().map_err(|_| {
            format!(
                "--preview: expected an address such as 127.0.0.1:8080 or [::1]:0, got '{addr}'"
            )
        })?;
        let server =
            Server::http(sock).map_err(|e| format!("--preview: cannot listen on {sock}: {e}"))?;
        let bound = server
            .server_addr()
            .to_ip()
            .ok_or_else(|| format!("--preview: {sock} is not an IP address"))?;
        let server = Arc::new(server);
        let shared = Arc::new(Shared {
            snapshot: Mutex::new(Snapshot {
                state: State::Loading,
                pass: 0,
                image: None,
                spp: 0,
                spp_max: 0,
                spp_mean: 0.0,
                spp_target: None,
                elapsed: Duration::ZERO,
                noise: None,
            }),
            cancel,
            start: Instant::now(),
        });
        let thread = {
            let (server, shared) = (server.clone(), shared.clone());
            std::thread::Builder::new()
                .name("preview".into())
                .spawn(move || {
                    for request in server.incoming_requests() {
                        respond(&shared, request);
                    }
                })
                .map_err(|e| format!("--preview: cannot start the server thread: {e}"))?
        };
        Ok(Preview {
            server,
            shared,
            thread: Some(thread),
            addr: bound,
        })
    }

    /// The address the server listens on (with the port chosen for port 0).
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// The page's URL.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// Publishes the film after a pass: its mean image, the samples per pixel done (`next`),
    /// the sample cap (if any) and the noise estimate E (see [`crate::progressive`]).
    pub fn publish(&self, film: &Film, next: &[u32], spp_target: Option<u32>) {
        let image = Arc::new(film.image());
        let (noise, _) = crate::progressive::relative_error(film);
        let n = next.len().max(1) as f64;
        let mut s = self.lock();
        s.pass += 1;
        s.image = Some(image);
        s.spp = next.iter().copied().min().unwrap_or(0);
        s.spp_max = next.iter().copied().max().unwrap_or(0);
        s.spp_mean = next.iter().map(|&k| k as f64).sum::<f64>() / n;
        s.spp_target = spp_target;
        s.elapsed = self.shared.start.elapsed();
        s.noise = noise.is_finite().then_some(noise);
        if s.state == State::Loading {
            s.state = State::Rendering;
        }
    }

    /// Marks the render as started (before its first pass) or ended.
    pub fn set_state(&self, state: State) {
        let mut s = self.lock();
        s.state = state;
        s.elapsed = self.shared.start.elapsed();
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Snapshot> {
        lock(&self.shared)
    }
}

impl Drop for Preview {
    fn drop(&mut self) {
        self.server.unblock();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The snapshot, also after a panic elsewhere (it is plain data, always consistent).
fn lock(shared: &Shared) -> std::sync::MutexGuard<'_, Snapshot> {
    shared
        .snapshot
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

fn header(name: &str, value: &str) -> Header {
    Header::from_bytes(name.as_bytes(), value.as_bytes()).expect("a valid header")
}

fn text(status: u16, body: &str) -> Response<std::io::Cursor<Vec<u8>>> {
    Response::from_string(body)
        .with_status_code(status)
        .with_header(header("Content-Type", "text/plain; charset=utf-8"))
}

fn respond(shared: &Shared, request: Request) {
    let response = route(shared, &request);
    // A client that went away is no concern of the render's.
    let _ = request.respond(response.with_header(header("Cache-Control", "no-store")));
}

fn route(shared: &Shared, request: &Request) -> Response<std::io::Cursor<Vec<u8>>> {
    if !host_allowed(request) {
        return text(403, "forbidden: unknown Host\n");
    }
    let url = request.url();
    let (path, query) = url.split_once('?').unwrap_or((url, ""));
    match (request.method(), path) {
        (Method::Get | Method::Head, "/" | "/index.html") => Response::from_string(PAGE)
            .with_header(header("Content-Type", "text/html; charset=utf-8")),
        (Method::Get | Method::Head, "/status.json") => Response::from_string(status_json(shared))
            .with_header(header("Content-Type", "application/json")),
        (Method::Get | Method::Head, "/image.png") => match png_options(query) {
            Err(e) => text(400, &format!("{e}\n")),
            Ok(opts) => image_response(shared, "image/png", |img, out| encode_png(out, img, &opts)),
        },
        (Method::Get | Method::Head, "/image.exr") => {
            image_response(shared, "image/x-exr", |img, out| {
                encode_exr(std::io::Cursor::new(out), img, false)
            })
        }
        (Method::Post, "/stop") => {
            if !origin_allowed(request) {
                return text(403, "forbidden: the stop request comes from another site\n");
            }
            shared.cancel.store(true, Ordering::SeqCst);
            let mut s = lock(shared);
            if s.state != State::Done {
                s.state = State::Stopping;
            }
            text(
                200,
                "stopping: the render writes its image and checkpoint\n",
            )
        }
        (_, "/stop") => text(405, "use POST /stop\n").with_header(header("Allow", "POST")),
        _ => text(404, "not found\n"),
    }
}

/// Encodes the latest image; 503 before the first pass.
fn image_response(
    shared: &Shared,
    mime: &str,
    encode: impl FnOnce(&Image, &mut Vec<u8>) -> Result<(), String>,
) -> Response<std::io::Cursor<Vec<u8>>> {
    let (image, pass) = {
        let s = lock(shared);
        (s.image.clone(), s.pass)
    };
    let Some(image) = image else {
        return text(503, "no pass has finished yet\n").with_header(header("Retry-After", "1"));
    };
    let mut bytes = Vec::new();
    match encode(&image, &mut bytes) {
        // With a Content-Length (not chunked), so that clients see the size.
        Ok(()) => Response::from_data(bytes)
            .with_chunked_threshold(usize::MAX)
            .with_header(header("Content-Type", mime))
            .with_header(header("X-Mcrt-Pass", &pass.to_string())),
        Err(e) => text(500, &format!("cannot encode the image: {e}\n")),
    }
}

/// The exposure and tone map of `/image.png` from its query (`exposure=EV&tonemap=NAME`).
fn png_options(query: &str) -> Result<WriteOptions, String> {
    let mut opts = WriteOptions::default();
    for pair in query.split('&').filter(|p| !p.is_empty()) {
        let (key, value) = pair.split_once('=').unwrap_or((pair, ""));
        match key {
            "exposure" => {
                let ev: f32 = value
                    .parse()
                    .map_err(|_| format!("exposure: expected a number, got '{value}'"))?;
                if !(ev.abs() <= MAX_EXPOSURE) {
                    return Err(format!(
                        "exposure: expected stops in [-{MAX_EXPOSURE}, {MAX_EXPOSURE}], got '{value}'"
                    ));
                }
                opts.exposure = ev;
            }
            "tonemap" => {
                opts.tonemap = match value {
                    "clamp" => ToneMap::Clamp,
                    "reinhard" => ToneMap::Reinhard,
                    "aces" => ToneMap::Aces,
                    _ => {
                        return Err(format!(
                            "tonemap: expected clamp, reinhard or aces, got '{value}'"
                        ))
                    }
                }
            }
            // Others (the page's cache-busting `pass`) are ignored.
            _ => {}
        }
    }
    Ok(opts)
}

fn status_json(shared: &Shared) -> String {
    let s = lock(shared);
    let (w, h) = s.image.as_ref().map_or((0, 0), |i| (i.width, i.height));
    let opt = |v: Option<String>| v.unwrap_or_else(|| "null".into());
    format!(
        "{{\"state\":\"{}\",\"pass\":{},\"spp\":{},\"spp_max\":{},\"spp_mean\":{:.3},\"spp_target\":{},\"elapsed\":{:.3},\"noise\":{},\"width\":{w},\"height\":{h}}}\n",
        s.state.name(),
        s.pass,
        s.spp,
        s.spp_max,
        s.spp_mean,
        opt(s.spp_target.map(|t| t.to_string())),
        s.elapsed.as_secs_f64(),
        opt(s.noise.map(|e| format!("{e:.6}"))),
    )
}

fn header_value<'a>(request: &'a Request, name: &'static str) -> Option<&'a str> {
    request
        .headers()
        .iter()
        .find(|h| h.field.equiv(name))
        .map(|h| h.value.as_str())
}

/// The host part of `host[:port]` or `[v6]:port`.
fn host_name(authority: &str) -> &str {
    if let Some(rest) = authority.strip_prefix('[') {
        return rest.split(']').next().unwrap_or(rest);
    }
    authority.rsplit_once(':').map_or(authority, |(h, _)| h)
}

/// A request may name the server by an IP address or `localhost`, not by another name: a page
/// of some other site whose name is made to resolve to 127.0.0.1 cannot read the preview.
fn host_allowed(request: &Request) -> bool {
    match header_value(request, "Host") {
        None => true,
        Some(h) => {
            let name = host_name(h.trim());
            name.eq_ignore_ascii_case("localhost") || name.parse::<IpAddr>().is_ok()
        }
    }
}

/// `/stop` from a browser carries an `Origin`; it must be this server's own (`http://` and
/// the request's `Host`).
fn origin_allowed(request: &Request) -> bool {
    match (
        header_value(request, "Origin"),
        header_value(request, "Host"),
    ) {
        (None, _) => true,
        (Some(origin), Some(host)) => origin.trim() == format!("http://{}", host.trim()),
        (Some(_), None) => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_query() {
        let o = png_options("exposure=-1.5&tonemap=aces&pass=3").unwrap();
        assert_eq!((o.exposure, o.tonemap), (-1.5, ToneMap::Aces));
        let o = png_options("").unwrap();
        assert_eq!((o.exposure, o.tonemap), (0.0, ToneMap::Clamp));
        for bad in [
            "exposure=nan",
            "exposure=1e9",
            "exposure=x",
            "tonemap=filmic",
        ] {
            assert!(png_options(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn host_names() {
        assert_eq!(host_name("127.0.0.1:8080"), "127.0.0.1");
        assert_eq!(host_name("[::1]:80"), "::1");
        assert_eq!(host_name("localhost"), "localhost");
        assert_eq!(host_name("evil.example:80"), "evil.example");
    }
}
