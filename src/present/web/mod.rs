//! The local web server behind `label --web` and `report --serve`: tiny_http on one thread,
//! guarded so that it is safe to leave running on a workstation.
//!
//! - It binds 127.0.0.1 unless told otherwise.
//! - A request whose Host or Origin is not the served address is refused with 403, which
//!   stops DNS rebinding and other sites' pages from driving the robot or deleting labels.
//! - Bodies are capped at [`MAX_BODY_BYTES`]; a bad request gets a 4xx with a one-line
//!   message and the server keeps running.
//!
//! The pages are plain HTML, CSS and JavaScript embedded in the binary.

pub(crate) mod labels_page;
pub(crate) mod report_route;
pub(crate) mod session;

use std::net::{IpAddr, SocketAddr};
use std::time::Duration;

use anyhow::Context as _;

/// How long a request's body may keep the server waiting (one shorter than its Content-Length,
/// say) before it gets 408.
pub(crate) const READ_TIMEOUT: Duration = Duration::from_secs(5);
/// The socket read timeout within [`READ_TIMEOUT`]: each wait for body bytes ends this soon, and
/// the deadline is checked between waits.
const READ_POLL: Duration = Duration::from_millis(500);

/// Gives the connection that `request` came on a read timeout, so that a body shorter than its
/// Content-Length ends in 408 instead of holding the server. tiny_http hands out no socket, so
/// the connection is found among the process's descriptors by its two addresses (Linux).
fn limit_body_wait(request: &tiny_http::Request, local: SocketAddr, timeout: Duration) {
    let Some(&remote) = request.remote_addr() else {
        return;
    };
    let Ok(fds) = std::fs::read_dir("/proc/self/fd") else {
        return;
    };
    let value = libc::timeval {
        tv_sec: timeout.as_secs() as libc::time_t,
        tv_usec: timeout.subsec_micros() as libc::suseconds_t,
    };
    for fd in fds
        .flatten()
        .filter_map(|e| e.file_name().to_str()?.parse::<i32>().ok())
    {
        if socket_address(fd, libc::getpeername) == Some(remote)
            && socket_address(fd, libc::getsockname).is_some_and(|a| a.port() == local.port())
        {
            // SAFETY: `fd` is an open socket of this process (its addresses were just read);
            // SO_RCVTIMEO takes a timeval of the size given.
            unsafe {
                libc::setsockopt(
                    fd,
                    libc::SOL_SOCKET,
                    libc::SO_RCVTIMEO,
                    (&value as *const libc::timeval).cast(),
                    std::mem::size_of::<libc::timeval>() as libc::socklen_t,
                );
            }
        }
    }
}

/// A socket's own or peer address by `query` (getsockname or getpeername); `None` for a
/// descriptor that is not an IP socket.
fn socket_address(
    fd: i32,
    query: unsafe extern "C" fn(i32, *mut libc::sockaddr, *mut libc::socklen_t) -> i32,
) -> Option<SocketAddr> {
    // SAFETY: sockaddr_storage is plain data that may be zeroed, and large enough for any
    // address the call writes; the length tells the call its size.
    let mut storage: libc::sockaddr_storage = unsafe { std::mem::zeroed() };
    let mut len = std::mem::size_of::<libc::sockaddr_storage>() as libc::socklen_t;
    // SAFETY: the pointers are to the storage and its length, valid for the call.
    if unsafe {
        query(
            fd,
            (&mut storage as *mut libc::sockaddr_storage).cast(),
            &mut len,
        )
    } != 0
    {
        return None;
    }
    match i32::from(storage.ss_family) {
        libc::AF_INET => {
            // SAFETY: the family says the storage holds a sockaddr_in.
            let a: libc::sockaddr_in =
                unsafe { std::ptr::read((&storage as *const libc::sockaddr_storage).cast()) };
            let ip = std::net::Ipv4Addr::from(u32::from_be(a.sin_addr.s_addr));
            Some(SocketAddr::new(ip.into(), u16::from_be(a.sin_port)))
        }
        libc::AF_INET6 => {
            // SAFETY: the family says the storage holds a sockaddr_in6.
            let a: libc::sockaddr_in6 =
                unsafe { std::ptr::read((&storage as *const libc::sockaddr_storage).cast()) };
            let ip = std::net::Ipv6Addr::from(a.sin6_addr.s6_addr);
            Some(SocketAddr::new(ip.into(), u16::from_be(a.sin6_port)))
        }
        _ => None,
    }
}

/// The largest request body accepted; the API's bodies are a few dozen bytes.
pub(crate) const MAX_BODY_BYTES: usize = 16 * 1024;

/// The shared stylesheet and helpers of every page.
const STYLE_CSS: &str = include_str!("page/style.css");

/// The head and header every page shares; `{{page}}` names it, `{{nav}}` holds the links.
const FRAME_HTML: &str = include_str!("page/frame.html");

/// The pages the header links to, in order: path and label.
const NAV: [(&str, &str); 3] = [("/", "Label"), ("/labels", "Labels"), ("/report", "Report")];

/// A whole page: the shared frame around `main` (the page's own markup from `<main>` on), with
/// the header naming `page` and marking the link to `path` as the current one.
pub(crate) fn framed_page(page: &str, path: &str, main: &str) -> String {
    let nav: String = NAV
        .iter()
        .map(|&(href, text)| {
            let here = if href == path { " class=\"here\"" } else { "" };
            format!("<a{here} href=\"{href}\">{text}</a>")
        })
        .collect();
    FRAME_HTML
        .replace("{{page}}", page)
        .replace("{{nav}}", &nav)
        + main
}

/// A parsed request, as the routes see it.
pub(crate) struct Request {
    /// `GET`, `POST`, `DELETE`, …
    pub(crate) method: String,
    /// The path, without the query.
    pub(crate) path: String,
    /// The body (at most [`MAX_BODY_BYTES`]).
    pub(crate) body: Vec<u8>,
}

impl Request {
    /// The body as a JSON object, or a 400 saying what is wrong with it.
    pub(crate) fn json(&self) -> Result<serde_json::Value, Reply> {
        let value: serde_json::Value = serde_json::from_slice(&self.body)
            .map_err(|e| Reply::error(400, &format!("the body is not valid JSON: {e}")))?;
        if !value.is_object() {
            return Err(Reply::error(400, "the body must be a JSON object"));
        }
        Ok(value)
    }
}

/// A response.
pub(crate) struct Reply {
    pub(crate) status: u16,
    pub(crate) content_type: &'static str,
    pub(crate) body: Vec<u8>,
}

impl Reply {
    /// A JSON body with status 200.
    pub(crate) fn json(value: &serde_json::Value) -> Self {
        Reply {
            status: 200,
            content_type: "application/json",
            body: serde_json::to_vec(value).expect("JSON values serialise"),
        }
    }

    /// A one-line error, as JSON `{"error": …}` so that the page can show it.
    pub(crate) fn error(status: u16, message: &str) -> Self {
        let mut reply = Reply::json(&serde_json::json!({ "error": message }));
        reply.status = status;
        reply
    }

    /// Bytes of a given type.
    pub(crate) fn bytes(content_type: &'static str, body: Vec<u8>) -> Self {
        Reply {
            status: 200,
            content_type,
            body,
        }
    }

    /// An embedded text asset.
    pub(crate) fn text(content_type: &'static str, text: &str) -> Self {
        Reply::bytes(content_type, text.as_bytes().to_vec())
    }

    /// 404 naming the path.
    pub(crate) fn not_found(path: &str) -> Self {
        Reply::error(404, &format!("no such page: {path}"))
    }
}

/// Answers one request; `None` when the path is not this route set's.
pub(crate) type Route<'a> = dyn Fn(&Request) -> Option<Reply> + Sync + 'a;

/// The bound server.
pub(crate) struct WebServer {
    server: tiny_http::Server,
    address: SocketAddr,
}

impl WebServer {
    /// Binds `host:port` (port 0 picks a free one).
    pub(crate) fn bind(host: IpAddr, port: u16) -> anyhow::Result<Self> {
        let wanted = SocketAddr::new(host, port);
        let refused = |e: &dyn std::fmt::Display| {
            anyhow::anyhow!(
                "cannot serve on {wanted}: {e} (pick another --port, or 0 for any free one)"
            )
        };
        let server = tiny_http::Server::http(wanted).map_err(|e| refused(&e))?;
        let address = server
            .server_addr()
            .to_ip()
            .context("the server has no IP address")?;
        if !host.is_loopback() {
            tracing::warn!(
                "serving on {address}: other machines on the network can reach this page and run the robot; use --host 127.0.0.1 to keep it local"
            );
        }
        Ok(WebServer { server, address })
    }

    /// The address it serves.
    pub(crate) fn url(&self) -> String {
        format!("http://{}/", self.host_port())
    }

    /// `IP:PORT` as a browser is told to open it: loopback when bound to every interface.
    fn host_port(&self) -> String {
        if self.address.ip().is_unspecified() {
            return format!("127.0.0.1:{}", self.address.port());
        }
        match self.address.ip() {
            IpAddr::V6(ip) => format!("[{ip}]:{}", self.address.port()),
            IpAddr::V4(ip) => format!("{ip}:{}", self.address.port()),
        }
    }

    /// Whether a Host value names this server: the bound address, and `localhost` and
    /// `127.0.0.1` on loopback. Bound to every interface (0.0.0.0 or ::), any IP address with
    /// the port is accepted too, since the machine's own addresses are not known here; a DNS
    /// rebinding page always sends its own host *name*, which stays refused.
    fn names_this_server(&self, host: &str) -> bool {
        let port = self.address.port();
        let ip = self.address.ip();
        let mut names = vec![self.host_port()];
        if ip.is_loopback() || ip.is_unspecified() {
            names.push(format!("localhost:{port}"));
            names.push(format!("127.0.0.1:{port}"));
        }
        if names.iter().any(|n| n.eq_ignore_ascii_case(host)) {
            return true;
        }
        ip.is_unspecified() && host.parse::<SocketAddr>().is_ok_and(|a| a.port() == port)
    }

    /// Serves `routes` (tried in order) until `stop` says so; checks it every 100 ms.
    pub(crate) fn serve(&self, routes: &[&Route<'_>], stop: &dyn Fn() -> bool) {
        while !stop() {
            let mut request = match self.server.recv_timeout(Duration::from_millis(100)) {
                Ok(Some(request)) => request,
                Ok(None) => continue,
                Err(e) => {
                    tracing::warn!("web server: {e}");
                    continue;
                }
            };
            limit_body_wait(&request, self.address, READ_POLL);
            let reply = match self.guard(&request).and_then(|()| read_body(&mut request)) {
                Ok(body) => route(
                    &Request {
                        method: request.method().as_str().to_owned(),
                        path: request.url().split('?').next().unwrap_or("").to_owned(),
                        body,
                    },
                    routes,
                ),
                Err(refusal) => refusal,
            };
            let header = tiny_http::Header::from_bytes("Content-Type", reply.content_type)
                .expect("content types are valid header values");
            let response = tiny_http::Response::from_data(reply.body)
                .with_status_code(reply.status)
                .with_header(header)
                .with_header(
                    tiny_http::Header::from_bytes("Cache-Control", "no-store")
                        .expect("a valid header"),
                );
            // A client that went away is not the server's problem.
            let _ = request.respond(response);
        }
    }
}

impl WebServer {
    /// Refuses requests that are not for this server (Host, Origin) or too large.
    fn guard(&self, request: &tiny_http::Request) -> Result<(), Reply> {
        let header = |name: &'static str| {
            request
                .headers()
                .iter()
                .find(|h| h.field.equiv(name))
                .map(|h| h.value.as_str().to_owned())
        };
        let host = header("Host").unwrap_or_default();
        if !self.names_this_server(&host) {
            return Err(Reply::error(
                403,
                &format!(
                    "Host '{host}' is not this server; open http://{} instead",
                    self.host_port()
                ),
            ));
        }
        if let Some(origin) = header("Origin") {
            let ours = origin
                .strip_prefix("http://")
                .is_some_and(|o| self.names_this_server(o));
            if !ours {
                return Err(Reply::error(
                    403,
                    &format!("requests from the page at '{origin}' are refused"),
                ));
            }
        }
        if request.body_length().is_some_and(|n| n > MAX_BODY_BYTES) {
            return Err(Reply::error(
                413,
                &format!("the body is larger than {MAX_BODY_BYTES} bytes"),
            ));
        }
        Ok(())
    }
}

/// The first route that knows the path answers; the stylesheet is shared by all pages.
fn route(request: &Request, routes: &[&Route<'_>]) -> Reply {
    if request.path == "/style.css" {
        return Reply::text("text/css; charset=utf-8", STYLE_CSS);
    }
    routes
        .iter()
        .find_map(|route| route(request))
        .unwrap_or_else(|| Reply::not_found(&request.path))
}

/// Reads at most [`MAX_BODY_BYTES`] + 1 bytes of the body; more is a 413.
fn read_body(request: &mut tiny_http::Request) -> Result<Vec<u8>, Reply> {
    let start = std::time::Instant::now();
    let reader = request.as_reader();
    let mut body = Vec::new();
    let mut chunk = [0u8; 4096];
    loop {
        match reader.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => {
                body.extend_from_slice(&chunk[..n]);
                if body.len() > MAX_BODY_BYTES {
                    return Err(Reply::error(
                        413,
                        &format!("the body is larger than {MAX_BODY_BYTES} bytes"),
                    ));
                }
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) && start.elapsed() < READ_TIMEOUT => {}
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                return Err(Reply::error(
                    408,
                    &format!(
                        "the body stopped short of its Content-Length for {} s",
                        READ_TIMEOUT.as_secs()
                    ),
                ))
            }
            Err(e) => return Err(Reply::error(400, &format!("reading the body: {e}"))),
        }
    }
    Ok(body)
}
