//! `mcrt render --preview`: the live preview server, over HTTP from a plain TCP client, and
//! (ignored by default, needs Debian's `chromium`) in a real headless browser.

mod common;

use common::cli::*;
use common::project_path;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A render with a preview, its server's address, and its stderr so far.
struct Rendering {
    child: Child,
    addr: SocketAddr,
    stderr: std::sync::mpsc::Receiver<String>,
}

impl Drop for Rendering {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts `mcrt render` of the Cornell box at 64² with far more samples than the test waits
/// for, with `--preview` on loopback, and reads the printed URL.
// Every way out kills and waits for the child (Rendering's Drop; the panics above it);
// clippy does not see through the Drop.
#[allow(clippy::zombie_processes)]
fn start(out: &std::path::Path, extra: &[&str]) -> Rendering {
    let mut child = Command::new(BIN)
        .arg("render")
        .arg(project_path("scenes/cornell-box.toml"))
        .args([
            "--width",
            "64",
            "--height",
            "64",
            "--spp",
            "1000000",
            "--threads",
            "2",
        ])
        .args(["--preview", "--quiet", "-o"])
        .arg(out)
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("cannot run mcrt");
    let stderr = BufReader::new(child.stderr.take().unwrap());
    let (tx, rx) = std::sync::mpsc::channel();
    // Drain stderr (so the render never blocks on it) and pass the lines on.
    std::thread::spawn(move || {
        for line in stderr.lines().map_while(Result::ok) {
            let _ = tx.send(line);
        }
    });
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        let Ok(line) = rx.recv_timeout(left) else {
            let _ = child.kill();
            let _ = child.wait();
            panic!("mcrt printed no preview URL within 60 s");
        };
        if let Some(url) = line.strip_prefix("preview: http://") {
            let Ok(addr) = url.trim_end_matches('/').parse::<SocketAddr>() else {
                let _ = child.kill();
                let _ = child.wait();
                panic!("not an address: {line}");
            };
            let r = Rendering {
                child,
                addr,
                stderr: rx,
            };
            assert!(addr.ip().is_loopback(), "{addr} is not loopback");
            assert_ne!(addr.port(), 0, "the chosen port is printed");
            return r;
        }
    }
}

/// A response: status code, headers (lower-case names), body.
struct Reply {
    status: u16,
    headers: Vec<(String, String)>,
    body: Vec<u8>,
}

impl Reply {
    fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
    }
    fn text(&self) -> String {
        String::from_utf8_lossy(&self.body).into_owned()
    }
}

/// One HTTP/1.0 request (the server then answers with a plain body and closes).
fn request(addr: SocketAddr, method: &str, path: &str, headers: &[&str]) -> Reply {
    request_version(addr, "HTTP/1.0", method, path, headers)
}

/// One request; the body is read to its Content-Length, else to the end of the connection.
fn request_version(
    addr: SocketAddr,
    version: &str,
    method: &str,
    path: &str,
    headers: &[&str],
) -> Reply {
    let mut s = TcpStream::connect_timeout(&addr, Duration::from_secs(10)).expect("connect");
    s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    let mut req = format!("{method} {path} {version}\r\n");
    if !headers.iter().any(|h| h.starts_with("Host:")) {
        req += &format!("Host: {addr}\r\n");
    }
    for h in headers {
        req += &format!("{h}\r\n");
    }
    req += "Content-Length: 0\r\n\r\n";
    s.write_all(req.as_bytes()).unwrap();
    let mut raw = Vec::new();
    let mut buf = [0u8; 65536];
    let split = loop {
        if let Some(p) = raw.windows(4).position(|w| w == b"\r\n\r\n") {
            break p;
        }
        let n = s.read(&mut buf).expect("read the response");
        assert!(
            n > 0,
            "the connection closed before a complete response head"
        );
        raw.extend_from_slice(&buf[..n]);
    };
    let head = String::from_utf8_lossy(&raw[..split]).into_owned();
    let mut lines = head.split("\r\n");
    let status = lines
        .next()
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|c| c.parse().ok())
        .expect("a status line");
    let headers: Vec<(String, String)> = lines
        .filter_map(|l| l.split_once(':'))
        .map(|(n, v)| (n.trim().to_ascii_lowercase(), v.trim().to_string()))
        .collect();
    let mut body = raw[split + 4..].to_vec();
    let length = headers
        .iter()
        .find(|(n, _)| n == "content-length")
        .and_then(|(_, v)| v.parse::<usize>().ok());
    match length {
        Some(len) => {
            while body.len() < len {
                let n = s.read(&mut buf).expect("read the body");
                assert!(
                    n > 0,
                    "the connection closed {} bytes into a body of {len}",
                    body.len()
                );
                body.extend_from_slice(&buf[..n]);
            }
            body.truncate(len);
        }
        None => {
            s.read_to_end(&mut body).expect("read the body");
        }
    }
    Reply {
        status,
        headers,
        body,
    }
}

fn get(addr: SocketAddr, path: &str) -> Reply {
    request(addr, "GET", path, &[])
}

/// A number field of the flat JSON object of /status.json (null: None).
fn field(json: &str, name: &str) -> Option<f64> {
    let key = format!("\"{name}\":");
    let rest = &json[json
        .find(&key)
        .unwrap_or_else(|| panic!("no {name} in {json}"))
        + key.len()..];
    let value = rest.split([',', '}']).next().unwrap().trim();
    if value == "null" {
        None
    } else {
        Some(value.parse().unwrap_or_else(|_| panic!("{name}: {value}")))
    }
}

/// Polls /status.json until `done` holds for it (at most 60 s).
fn wait_status(addr: SocketAddr, done: impl Fn(&str) -> bool) -> String {
    let t = Instant::now();
    loop {
        let r = get(addr, "/status.json");
        assert_eq!(r.status, 200);
        let json = r.text();
        if done(&json) {
            return json;
        }
        assert!(
            t.elapsed() < Duration::from_secs(60),
            "status stuck at {json}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn decode_png(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
    let dec = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = dec.read_info().expect("a PNG");
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).expect("PNG image data");
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

fn mean(v: &[u8]) -> f64 {
    v.iter().map(|&b| b as f64).sum::<f64>() / v.len().max(1) as f64
}

/// The page, the status, the PNG and the EXR are served while the render runs; the samples
/// grow from pass to pass; the PNG's exposure applies; POST /stop ends the render like
/// SIGINT, with its image and checkpoint written.
#[test]
fn preview_serves_the_converging_image_and_stops() {
    let dir = TempDir::new("preview");
    let out = dir.path().join("box.png");
    let mut r = start(&out, &[]);
    let addr = r.addr;

    let page = get(addr, "/");
    assert_eq!(page.status, 200);
    assert!(page
        .header("content-type")
        .unwrap()
        .starts_with("text/html"));
    let html = page.text();
    for needle in ["/status.json", "/image.png", "/stop", "exposure", "tonemap"] {
        assert!(html.contains(needle), "the page lacks {needle}");
    }

    // Two different passes, the second with more samples per pixel.
    let first = wait_status(addr, |j| field(j, "pass").unwrap() >= 1.0);
    let (pass1, spp1) = (
        field(&first, "pass").unwrap(),
        field(&first, "spp").unwrap(),
    );
    assert!(first.contains("\"state\":\"rendering\""), "{first}");
    assert!(spp1 >= 1.0, "{first}");
    assert_eq!(field(&first, "width"), Some(64.0));
    assert_eq!(field(&first, "spp_target"), Some(1e6));
    let png = get(addr, "/image.png");
    assert_eq!(png.status, 200, "{}", png.text());
    assert_eq!(png.header("content-type"), Some("image/png"));
    let (w, h, rgb) = decode_png(&png.body);
    assert_eq!((w, h, rgb.len()), (64, 64, 64 * 64 * 3));
    assert!(mean(&rgb) > 5.0, "the Cornell box is not black");
    let second = wait_status(addr, |j| field(j, "pass").unwrap() > pass1 + 1.0);
    let spp2 = field(&second, "spp").unwrap();
    assert!(spp2 > spp1, "spp did not grow: {first} then {second}");
    assert!(field(&second, "elapsed").unwrap() >= field(&first, "elapsed").unwrap());
    let noise = field(&second, "noise").expect("a noise estimate");
    assert!(noise > 0.0 && noise < 10.0, "{second}");

    // Exposure is applied to the PNG; a bad one is refused.
    let dark = get(addr, "/image.png?exposure=-4&tonemap=reinhard");
    assert_eq!(dark.status, 200);
    let (_, _, dark_rgb) = decode_png(&dark.body);
    assert!(mean(&dark_rgb) < mean(&rgb), "exposure -4 is not darker");
    assert_eq!(get(addr, "/image.png?exposure=nan").status, 400);
    assert_eq!(get(addr, "/image.png?tonemap=filmic").status, 400);

    let exr = get(addr, "/image.exr");
    assert_eq!(exr.status, 200);
    let exr_path = dir.path().join("snapshot.exr");
    std::fs::write(&exr_path, &exr.body).unwrap();
    let snap = mcrt::image::read_exr(&exr_path).expect("the EXR decodes");
    assert_eq!((snap.width, snap.height), (64, 64));
    assert!(snap
        .pixels
        .iter()
        .all(|p| p.is_finite() && p.min_element() >= 0.0));

    // Only the stop button controls the render, and only by POST from its own page.
    assert_eq!(get(addr, "/stop").status, 405);
    assert_eq!(get(addr, "/nothing").status, 404);
    let foreign = request(addr, "POST", "/stop", &["Origin: http://evil.example"]);
    assert_eq!(foreign.status, 403);
    let rebound = request(addr, "GET", "/status.json", &["Host: evil.example:80"]);
    assert_eq!(rebound.status, 403, "a foreign Host name is refused");
    assert!(
        r.child.try_wait().unwrap().is_none(),
        "refused requests stopped the render"
    );

    let origin = format!("Origin: http://{addr}");
    let stop = request(addr, "POST", "/stop", &[&origin]);
    assert_eq!(stop.status, 200, "{}", stop.text());
    let t = Instant::now();
    let status = loop {
        if let Some(s) = r.child.try_wait().unwrap() {
            break s;
        }
        assert!(
            t.elapsed() < Duration::from_secs(60),
            "POST /stop did not end the render"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    let err: Vec<String> = r.stderr.try_iter().collect();
    assert_eq!(status.code(), Some(130), "{err:?}");
    let written = std::fs::read(&out).expect("the image is written");
    let (w, h, _) = decode_png(&written);
    assert_eq!((w, h), (64, 64));
    let ckpt = mcrt::checkpoint::read_checkpoint(&dir.path().join("box.checkpoint.exr"))
        .expect("a checkpoint is written");
    let lo = *ckpt.next.iter().min().unwrap();
    assert!(
        lo as f64 >= spp2 && lo < 1_000_000,
        "checkpoint at {lo} spp"
    );
}

/// A bad --preview address is refused before anything is rendered.
#[test]
fn preview_bad_address_is_a_usage_error() {
    let dir = TempDir::new("preview-bad");
    let out = dir.path().join("x.png");
    for addr in ["nowhere", "127.0.0.1:99999"] {
        let o = run(&[
            "render".as_ref(),
            project_path("scenes/cornell-box.toml").as_os_str(),
            "--preview".as_ref(),
            addr.as_ref(),
            "-o".as_ref(),
            out.as_os_str(),
        ]);
        let err = stderr_of(&o);
        assert_eq!(o.status.code(), Some(2), "{addr}: {err}");
        assert!(err.contains("--preview"), "{err}");
        assert!(!out.exists());
    }
}

/// The page in a real browser: headless Chromium (Debian's `chromium`) loads it and the image
/// element follows the passes. The page sets its title to the pass whose image has loaded;
/// Chromium's DevTools HTTP endpoint (/json/list) reports the title, which must name at least
/// two different passes. Run with `cargo test --test preview -- --ignored`.
#[test]
#[ignore = "needs Debian's chromium (apt-get install chromium)"]
fn preview_updates_in_headless_chromium() {
    let chromium = ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|c| {
            Command::new(c)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        })
        .expect("no chromium on PATH (apt-get install chromium)");
    let dir = TempDir::new("preview-chromium");
    let out = dir.path().join("box.png");
    let r = start(&out, &[]);
    let profile = dir.path().join("profile");
    let mut browser = Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--no-first-run",
            "--remote-debugging-address=127.0.0.1",
            "--remote-debugging-port=0",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("http://{}/", r.addr))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("cannot start chromium");
    let result = (|| -> Result<Vec<String>, String> {
        // Chromium writes the DevTools port it chose into the profile.
        let port_file = profile.join("DevToolsActivePort");
        let t = Instant::now();
        let port: u16 = loop {
            if let Some(p) = std::fs::read_to_string(&port_file)
                .ok()
                .and_then(|s| s.lines().next().and_then(|l| l.trim().parse().ok()))
            {
                break p;
            }
            if t.elapsed() > Duration::from_secs(60) {
                return Err("chromium wrote no DevToolsActivePort".into());
            }
            std::thread::sleep(Duration::from_millis(100));
        };
        let devtools: SocketAddr = ([127, 0, 0, 1], port).into();
        let mut titles: Vec<String> = Vec::new();
        let t = Instant::now();
        while t.elapsed() < Duration::from_secs(60) {
            // Chromium's DevTools server speaks HTTP/1.1 only.
            let list = request_version(devtools, "HTTP/1.1", "GET", "/json/list", &[]).text();
            for title in list
                .lines()
                .filter_map(|l| l.trim().strip_prefix("\"title\": \""))
                .map(|t| t.trim_end_matches(['"', ',']).to_string())
                .filter(|t| t.starts_with("mcrt preview: pass"))
            {
                if !titles.contains(&title) {
                    eprintln!("chromium shows: {title}");
                    titles.push(title);
                }
            }
            if titles.len() >= 3 {
                return Ok(titles);
            }
            std::thread::sleep(Duration::from_millis(200));
        }
        Err(format!(
            "the page's image did not update: titles {titles:?}"
        ))
    })();
    let _ = browser.kill();
    let _ = browser.wait();
    let titles = result.unwrap();
    // The passes whose images loaded, in the order seen, must increase.
    let passes: Vec<u32> = titles
        .iter()
        .map(|t| {
            t["mcrt preview: pass ".len()..]
                .split(',')
                .next()
                .unwrap()
                .parse()
                .unwrap()
        })
        .collect();
    assert!(passes.windows(2).all(|w| w[0] < w[1]), "{titles:?}");
}
