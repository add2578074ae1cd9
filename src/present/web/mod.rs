//! The local web server behind `label --web` and `report --serve`: requests read by
//! [`http`] and answered on one thread, guarded so that it is safe to leave running on a
//! workstation.
//!
//! - It binds 127.0.0.1 unless told otherwise.
//! - A request whose Host or Origin is not the served address is refused with 403, which
//!   stops DNS rebinding and other sites' pages from driving the robot or deleting labels.
//! - Bodies are capped at [`http::MAX_BODY_BYTES`], and a request must arrive within
//!   [`http::READ_TIMEOUT`]; a bad request gets a 4xx with a one-line message and the server
//!   keeps running.
//!
//! The pages are plain HTML, CSS and JavaScript embedded in the binary.

mod http;
pub(crate) mod labels_page;
pub(crate) mod report_route;
pub(crate) mod session;

use std::net::{IpAddr, SocketAddr};
use std::time::Duration;

pub(crate) use http::Reply;
use http::{HttpListener, Incoming};

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
    /// The body (at most [`http::MAX_BODY_BYTES`]).
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

/// Answers one request; `None` when the path is not this route set's.
pub(crate) type Route<'a> = dyn Fn(&Request) -> Option<Reply> + Sync + 'a;

/// The bound server.
pub(crate) struct WebServer {
    server: HttpListener,
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
        let server = HttpListener::bind(wanted).map_err(|e| refused(&e))?;
        let address = server.address();
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
            let Some(request) = self.server.recv_timeout(Duration::from_millis(100)) else {
                continue;
            };
            let reply = match self.guard(&request) {
                Ok(()) => route(
                    &Request {
                        method: request.method.clone(),
                        path: request.target.split('?').next().unwrap_or("").to_owned(),
                        body: request.body.clone(),
                    },
                    routes,
                ),
                Err(refusal) => refusal,
            };
            request.respond(&reply);
        }
    }
}

impl WebServer {
    /// Refuses requests that are not for this server (Host, Origin); [`http`] has refused the
    /// malformed, the slow and the too large.
    fn guard(&self, request: &Incoming) -> Result<(), Reply> {
        let host = request.header("Host").unwrap_or_default();
        if !self.names_this_server(host) {
            return Err(Reply::error(
                403,
                &format!(
                    "Host '{host}' is not this server; open http://{} instead",
                    self.host_port()
                ),
            ));
        }
        if let Some(origin) = request.header("Origin") {
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
