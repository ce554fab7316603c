//! `drivebus gateway`: the CiA 309-3 ASCII gateway over the master, on
//! stdin/stdout (an interactive shell with line editing and history on a
//! terminal) or on TCP (`--listen`, what `cocomm -t HOST -p PORT` connects
//! to). Each TCP client has its own default node and SDO settings; all
//! share the master. Lines end in LF or CR LF; answers end in CR LF.

use std::io::IsTerminal;

use anyhow::{Context, anyhow};
use tokio::io::{AsyncBufReadExt, AsyncReadExt, AsyncWriteExt, BufReader};

use crate::args::{GatewayArgs, Global};
use crate::conn::Conn;
use drivebus_master::gateway::{self as exec, Session, proto};

/// Longest request line accepted (CANopenNode's buffer is 1000 bytes).
const MAX_LINE: usize = 64 * 1024;

/// Runs the gateway until stdin ends, Ctrl-C, or (TCP) for ever.
pub async fn run(g: &Global, a: &GatewayArgs) -> anyhow::Result<()> {
    let conn = Conn::open(g).await?;
    let r = match &a.listen {
        Some(addr) => serve_tcp(g, &conn, addr).await,
        None if !a.no_shell && std::io::stdin().is_terminal() && std::io::stdout().is_terminal() => {
            shell(g, &conn).await
        }
        None => serve_stdio(g, &conn).await,
    };
    let closed = conn.close().await;
    r?;
    closed
}

fn session(g: &Global, conn: &Conn) -> Session {
    Session::new(conn.master.clone(), g.node, conn.timeout, g.retries)
}

/// Reads lines (LF, CR LF), answers each; a line too long or not UTF-8 is
/// answered with a syntax error, never a panic.
async fn serve_lines<R, W>(mut s: Session, rd: R, mut wr: W) -> anyhow::Result<()>
where
    R: tokio::io::AsyncRead + Unpin,
    W: tokio::io::AsyncWrite + Unpin,
{
    let mut rd = BufReader::new(rd);
    let mut buf = Vec::new();
    loop {
        buf.clear();
        let n = AsyncReadExt::take(&mut rd, MAX_LINE as u64).read_until(b'\n', &mut buf).await?;
        if n == 0 {
            return Ok(());
        }
        let answer = match std::str::from_utf8(&buf) {
            Ok(line) if buf.ends_with(b"\n") || n < MAX_LINE => {
                s.line(line.trim_end_matches(['\r', '\n'])).await
            }
            _ => {
                if !buf.ends_with(b"\n") {
                    // Drop the rest of an overlong line.
                    let mut rest = Vec::new();
                    rd.read_until(b'\n', &mut rest).await?;
                }
                exec::error(0, proto::code::SYNTAX)
            }
        };
        wr.write_all(answer.as_bytes()).await?;
        wr.flush().await?;
    }
}

async fn serve_stdio(g: &Global, conn: &Conn) -> anyhow::Result<()> {
    let s = session(g, conn);
    tokio::select! {
        r = serve_lines(s, tokio::io::stdin(), tokio::io::stdout()) => r,
        r = crate::serve::wait_for_signal() => r,
        why = conn.master.lost() => Err(conn.lost(&why)),
    }
}

async fn serve_tcp(g: &Global, conn: &Conn, addr: &str) -> anyhow::Result<()> {
    let listener =
        tokio::net::TcpListener::bind(addr).await.with_context(|| format!("cannot listen on {addr}"))?;
    let local = listener.local_addr()?;
    // Tools wait for this line (like `serve`'s).
    crate::output::outln!("drivebus gateway: CiA 309-3 listening on {local}");
    let stop = crate::serve::wait_for_signal();
    tokio::pin!(stop);
    loop {
        tokio::select! {
            r = listener.accept() => {
                let (sock, peer) = r.context("accepting a gateway client")?;
                let _ = sock.set_nodelay(true);
                let s = session(g, conn);
                tokio::spawn(async move {
                    let (rd, wr) = sock.into_split();
                    if let Err(e) = serve_lines(s, rd, wr).await {
                        tracing::info!(%peer, error = %e, "gateway client gone");
                    }
                });
            }
            r = &mut stop => return r,
            why = conn.master.lost() => return Err(conn.lost(&why)),
        }
    }
}

/// An interactive shell: line editing and history (rustyline), `[n]` added
/// to lines typed without a sequence number.
async fn shell(g: &Global, conn: &Conn) -> anyhow::Result<()> {
    let (tx, mut rx) = tokio::sync::mpsc::channel::<(String, std::sync::mpsc::Sender<String>)>(1);
    let editor =
        std::thread::Builder::new().name("gateway-shell".into()).spawn(move || -> anyhow::Result<()> {
            let mut ed =
                rustyline::DefaultEditor::new().map_err(|e| anyhow!("cannot start the line editor: {e}"))?;
            let history = std::env::var_os("HOME")
                .map(|h| std::path::PathBuf::from(h).join(".drivebus_gateway_history"));
            if let Some(h) = &history {
                let _ = ed.load_history(h);
            }
            println!("drivebus gateway (CiA 309-3). `help` lists the commands; Ctrl-D ends.");
            let mut seq = 1u32;
            loop {
                match ed.readline("gateway> ") {
                    Ok(line) => {
                        let t = line.trim();
                        if !t.is_empty() {
                            let _ = ed.add_history_entry(t);
                        }
                        let full = if t.is_empty() || t.starts_with('[') || t.starts_with('#') {
                            t.to_owned()
                        } else {
                            format!("[{seq}] {t}")
                        };
                        seq = seq.wrapping_add(1);
                        let (back, answer) = std::sync::mpsc::channel();
                        if tx.blocking_send((full, back)).is_err() {
                            break;
                        }
                        if let Ok(a) = answer.recv() {
                            print!("{}", a.replace("\r\n", "\n"));
                        }
                    }
                    Err(rustyline::error::ReadlineError::Interrupted) => continue,
                    Err(_) => break,
                }
            }
            if let Some(h) = &history {
                let _ = ed.save_history(h);
            }
            Ok(())
        })?;
    let mut s = session(g, conn);
    loop {
        tokio::select! {
            m = rx.recv() => match m {
                Some((line, back)) => {
                    let _ = back.send(s.line(&line).await);
                }
                None => break,
            },
            // The editor thread waits in readline; the process ends with this error.
            why = conn.master.lost() => return Err(conn.lost(&why)),
        }
    }
    editor.join().map_err(|_| anyhow!("the line editor failed"))??;
    Ok(())
}
