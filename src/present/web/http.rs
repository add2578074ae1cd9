//! HTTP/1.1 over std's TCP listener: a thread accepts, a thread per connection reads one request
//! (head parsed by httparse, body by its Content-Length) under [`READ_TIMEOUT`], and the serving
//! thread gets it whole. Owning the sockets is what lets every read carry a deadline, so a client
//! that stalls holds nothing but its own thread, and only for that long.

use std::io::{Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

/// The largest request body accepted; the API's bodies are a few dozen bytes.
pub(crate) const MAX_BODY_BYTES: usize = 16 * 1024;

/// How long one request (head and body) may take to arrive before it gets 408: one whose body
/// stops short of its Content-Length, say.
pub(crate) const READ_TIMEOUT: Duration = Duration::from_secs(5);
/// The longest request head (request line and headers) accepted.
const MAX_HEAD_BYTES: usize = 16 * 1024;
/// The most headers a request may have.
const MAX_HEADERS: usize = 64;
/// After an early answer (408, 413, …) the connection's unread bytes are drained this long, so
/// that closing it does not reset the answer away before the client reads it.
const DRAIN: Duration = Duration::from_millis(500);

/// A request read whole, with the connection to answer it on.
pub(crate) struct Incoming {
    pub(crate) method: String,
    /// The request target as sent: path and query.
    pub(crate) target: String,
    headers: Vec<(String, String)>,
    pub(crate) body: Vec<u8>,
    stream: TcpStream,
}

impl Incoming {
    /// The first value of header `name` (any case).
    pub(crate) fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
    }

    /// Sends `reply` and closes the connection; a client that went away is not the server's
    /// problem.
    pub(crate) fn respond(mut self, reply: &Reply) {
        let _ = write_reply(&mut self.stream, reply, self.method != "HEAD");
        let _ = self.stream.shutdown(Shutdown::Both);
    }
}

/// The listening socket and the requests its connections have read.
pub(crate) struct HttpListener {
    address: SocketAddr,
    /// Behind a lock so that the server can be shared with the thread that serves it.
    requests: Mutex<mpsc::Receiver<Incoming>>,
    closing: Arc<AtomicBool>,
}

impl HttpListener {
    /// Binds `address` (port 0 picks a free one) and starts accepting.
    pub(crate) fn bind(address: SocketAddr) -> std::io::Result<Self> {
        let listener = TcpListener::bind(address)?;
        let address = listener.local_addr()?;
        let (sender, requests) = mpsc::channel();
        let closing = Arc::new(AtomicBool::new(false));
        let stop = Arc::clone(&closing);
        std::thread::Builder::new()
            .name("http-accept".into())
            .spawn(move || accept(&listener, &sender, &stop))?;
        Ok(Self {
            address,
            requests: Mutex::new(requests),
            closing,
        })
    }

    /// The bound address.
    pub(crate) fn address(&self) -> SocketAddr {
        self.address
    }

    /// The next request read whole, waiting at most `timeout`.
    pub(crate) fn recv_timeout(&self, timeout: Duration) -> Option<Incoming> {
        let requests = self.requests.lock().unwrap_or_else(|e| e.into_inner());
        requests.recv_timeout(timeout).ok()
    }
}

impl Drop for HttpListener {
    fn drop(&mut self) {
        self.closing.store(true, Ordering::SeqCst);
        // The accept thread blocks in accept(); a connection wakes it to see the flag.
        let wake = match self.address {
            SocketAddr::V4(a) if a.ip().is_unspecified() => {
                SocketAddr::new(std::net::Ipv4Addr::LOCALHOST.into(), a.port())
            }
            SocketAddr::V6(a) if a.ip().is_unspecified() => {
                SocketAddr::new(std::net::Ipv6Addr::LOCALHOST.into(), a.port())
            }
            other => other,
        };
        let _ = TcpStream::connect_timeout(&wake, Duration::from_millis(200));
    }
}

fn accept(listener: &TcpListener, sender: &mpsc::Sender<Incoming>, closing: &AtomicBool) {
    for stream in listener.incoming() {
        if closing.load(Ordering::SeqCst) {
            return;
        }
        let Ok(stream) = stream else { continue };
        let sender = sender.clone();
        let spawned = std::thread::Builder::new()
            .name("http-connection".into())
            .spawn(move || match read_request(stream) {
                Ok(request) => {
                    let _ = sender.send(request);
                }
                Err(Some((mut stream, reply))) => {
                    let _ = write_reply(&mut stream, &reply, true);
                    drain_and_close(stream);
                }
                Err(None) => {}
            });
        if let Err(e) = spawned {
            tracing::warn!("web server: cannot start a connection's thread: {e}");
        }
    }
}

/// What a bad request gets: `Some` answer on its stream, or `None` for a client that left.
type Refused = Option<(TcpStream, Reply)>;

/// Reads one request; `Err(Some(…))` holds the answer for a bad one, `Err(None)` a client that
/// left before sending anything.
fn read_request(mut stream: TcpStream) -> Result<Incoming, Refused> {
    let deadline = Instant::now() + READ_TIMEOUT;
    let mut chunk = [0u8; 4096];
    let (mut buffer, head_end) = match read_head(&mut stream, &mut chunk, deadline) {
        Ok(head) => head,
        Err(reply) => return Err(reply.map(|reply| (stream, reply))),
    };
    let Head {
        method,
        target,
        headers,
    } = match parse_head(&buffer[..head_end]) {
        Ok(head) => head,
        Err(reply) => return Err(Some((stream, reply))),
    };
    let bad = |stream: TcpStream, status: u16, message: &str| {
        Err(Some((stream, Reply::error(status, message))))
    };
    let header = |name: &str| {
        headers
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
    };
    if header("Transfer-Encoding").is_some() {
        return bad(
            stream,
            411,
            "chunked bodies are not accepted: send the body with a Content-Length",
        );
    }
    let length = match header("Content-Length").map(str::parse::<usize>) {
        None => 0,
        Some(Ok(length)) => length,
        Some(Err(_)) => return bad(stream, 400, "the Content-Length is not a number of bytes"),
    };
    if length > MAX_BODY_BYTES {
        return bad(
            stream,
            413,
            &format!("the body is larger than {MAX_BODY_BYTES} bytes"),
        );
    }
    if length > 0
        && header("Expect").is_some_and(|v| v.eq_ignore_ascii_case("100-continue"))
        && stream.write_all(b"HTTP/1.1 100 Continue\r\n\r\n").is_err()
    {
        return Err(None);
    }
    let body = buffer.split_off(head_end);
    let body = match read_body(&mut stream, &mut chunk, deadline, body, length) {
        Ok(body) => body,
        Err(reply) => return Err(Some((stream, reply))),
    };
    Ok(Incoming {
        method,
        target,
        headers,
        body,
        stream,
    })
}

/// Reads until the end of the request head: what was read, and where the head ends in it;
/// `Err(None)` when the client left mid-head (nobody would read an answer).
fn read_head(
    stream: &mut TcpStream,
    chunk: &mut [u8],
    deadline: Instant,
) -> Result<(Vec<u8>, usize), Option<Reply>> {
    let mut buffer = Vec::with_capacity(1024);
    loop {
        if let Some(end) = find_head_end(&buffer) {
            return Ok((buffer, end));
        }
        if buffer.len() > MAX_HEAD_BYTES {
            return Err(Some(Reply::error(
                431,
                &format!("the request head is larger than {MAX_HEAD_BYTES} bytes"),
            )));
        }
        match read_until(stream, chunk, deadline) {
            Ok(0) => return Err(None),
            Ok(n) => buffer.extend_from_slice(&chunk[..n]),
            Err(Read408) => {
                return Err(Some(Reply::error(
                    408,
                    &format!(
                        "the request head did not arrive within {} s",
                        READ_TIMEOUT.as_secs()
                    ),
                )))
            }
        }
    }
}

/// A request's head, parsed.
struct Head {
    method: String,
    target: String,
    headers: Vec<(String, String)>,
}

/// The method, target and headers of a request head.
fn parse_head(head: &[u8]) -> Result<Head, Reply> {
    let mut headers = [httparse::EMPTY_HEADER; MAX_HEADERS];
    let mut parsed = httparse::Request::new(&mut headers);
    if let Err(e) = parsed.parse(head) {
        let status = if e == httparse::Error::TooManyHeaders {
            431
        } else {
            400
        };
        return Err(Reply::error(
            status,
            &format!("malformed request head: {e}"),
        ));
    }
    let method = parsed.method.unwrap_or_default().to_owned();
    let target = parsed.path.unwrap_or_default().to_owned();
    let headers = parsed
        .headers
        .iter()
        .map(|h| {
            (
                h.name.to_owned(),
                String::from_utf8_lossy(h.value).trim().to_owned(),
            )
        })
        .collect();
    Ok(Head {
        method,
        target,
        headers,
    })
}

/// Reads the rest of a body of `length` bytes, `body` holding what came with the head.
fn read_body(
    stream: &mut TcpStream,
    chunk: &mut [u8],
    deadline: Instant,
    mut body: Vec<u8>,
    length: usize,
) -> Result<Vec<u8>, Reply> {
    while body.len() < length {
        match read_until(stream, chunk, deadline) {
            Ok(0) => {
                return Err(Reply::error(
                    400,
                    "the body ended short of its Content-Length",
                ))
            }
            Ok(n) => body.extend_from_slice(&chunk[..n]),
            Err(Read408) => {
                return Err(Reply::error(
                    408,
                    &format!(
                        "the body stopped short of its Content-Length for {} s",
                        READ_TIMEOUT.as_secs()
                    ),
                ))
            }
        }
    }
    // Bytes past the Content-Length would be a second request; each answer closes the
    // connection, so they are not read.
    body.truncate(length);
    Ok(body)
}

/// The deadline passed before the client sent what it announced.
struct Read408;

/// One read that gives up at `deadline`; `Ok(0)` when the client closed its side or failed.
fn read_until(
    stream: &mut TcpStream,
    chunk: &mut [u8],
    deadline: Instant,
) -> Result<usize, Read408> {
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return Err(Read408);
        }
        if stream.set_read_timeout(Some(left)).is_err() {
            return Ok(0);
        }
        match stream.read(chunk) {
            Ok(n) => return Ok(n),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) => {}
            Err(_) => return Ok(0),
        }
    }
}

/// Where the head's blank line ends, if it has arrived.
fn find_head_end(buffer: &[u8]) -> Option<usize> {
    buffer
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .map(|p| p + 4)
}

fn write_reply(stream: &mut TcpStream, reply: &Reply, with_body: bool) -> std::io::Result<()> {
    let head = format!(
        "HTTP/1.1 {} {}\r\nContent-Type: {}\r\nContent-Length: {}\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n",
        reply.status,
        reason(reply.status),
        reply.content_type,
        reply.body.len()
    );
    stream.write_all(head.as_bytes())?;
    if with_body {
        stream.write_all(&reply.body)?;
    }
    stream.flush()
}

/// Closes our side, then reads what the client still sends for a moment: closing a socket
/// with unread bytes resets the connection, and the client may lose the answer with it.
fn drain_and_close(mut stream: TcpStream) {
    let _ = stream.shutdown(Shutdown::Write);
    let deadline = Instant::now() + DRAIN;
    let mut sink = [0u8; 4096];
    while let Ok(n) = read_until(&mut stream, &mut sink, deadline) {
        if n == 0 {
            break;
        }
    }
}

fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        408 => "Request Timeout",
        409 => "Conflict",
        411 => "Length Required",
        413 => "Content Too Large",
        431 => "Request Header Fields Too Large",
        500 => "Internal Server Error",
        503 => "Service Unavailable",
        _ => "",
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

#[cfg(test)]
mod tests {
    use super::*;

    fn exchange(listener: &HttpListener, raw: &[u8]) -> String {
        let mut client = TcpStream::connect(listener.address()).unwrap();
        client.write_all(raw).unwrap();
        if let Some(request) = listener.recv_timeout(Duration::from_secs(2)) {
            let method = request.method.clone();
            let target = request.target.clone();
            let body = request.body.clone();
            let host = request.header("host").map(str::to_owned);
            request.respond(&Reply::text("text/plain", "ok"));
            let mut answer = String::new();
            client.read_to_string(&mut answer).unwrap();
            let seen = format!(
                "{method} {target} {host:?} {}",
                String::from_utf8_lossy(&body)
            );
            return format!("{seen}\n{answer}");
        }
        client
            .set_read_timeout(Some(Duration::from_secs(10)))
            .unwrap();
        let mut answer = String::new();
        let _ = client.read_to_string(&mut answer);
        answer
    }

    fn listener() -> HttpListener {
        HttpListener::bind("127.0.0.1:0".parse().unwrap()).unwrap()
    }

    #[test]
    fn a_whole_request_reaches_the_server_and_its_answer_closes_the_connection() {
        let listener = listener();
        let text = exchange(
            &listener,
            b"POST /api/x?y=1 HTTP/1.1\r\nHost: a\r\nContent-Length: 5\r\n\r\nhello",
        );
        assert!(
            text.starts_with("POST /api/x?y=1 Some(\"a\") hello\nHTTP/1.1 200 OK\r\n"),
            "{text}"
        );
        assert!(text.contains("Connection: close\r\n"), "{text}");
        assert!(text.ends_with("\r\n\r\nok"), "{text}");
    }

    #[test]
    fn bad_heads_and_bodies_get_their_status_from_the_connection() {
        let listener = listener();
        let rows: [(&[u8], &str); 4] = [
            (b"NOT HTTP AT ALL\r\n\r\n", "HTTP/1.1 400 "),
            (
                b"POST / HTTP/1.1\r\nContent-Length: 99999999\r\n\r\n",
                "HTTP/1.1 413 ",
            ),
            (
                b"POST / HTTP/1.1\r\nContent-Length: ten\r\n\r\n",
                "HTTP/1.1 400 ",
            ),
            (
                b"POST / HTTP/1.1\r\nTransfer-Encoding: chunked\r\n\r\n",
                "HTTP/1.1 411 ",
            ),
        ];
        for (raw, status) in rows {
            let answer = exchange(&listener, raw);
            assert!(
                answer.starts_with(status),
                "{}: {answer}",
                String::from_utf8_lossy(raw)
            );
        }
    }

    #[test]
    fn a_body_short_of_its_length_gets_408_after_the_timeout_whatever_its_size() {
        let listener = listener();
        for length in [10, 5000] {
            let start = Instant::now();
            let raw = format!("POST / HTTP/1.1\r\nContent-Length: {length}\r\n\r\n{{}}");
            let answer = exchange(&listener, raw.as_bytes());
            assert!(answer.starts_with("HTTP/1.1 408 "), "{length}: {answer}");
            assert!(start.elapsed() >= READ_TIMEOUT, "{length}");
        }
    }
}
