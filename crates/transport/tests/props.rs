//! Property tests: parsers of outside input never panic and round-trip.

use drivebus_transport::slcan::codec::{self as slcan, LineSplitter, Token};
use drivebus_transport::slcan::device::SlcanDevice;
use drivebus_transport::socketcand::proto::{self, Message, Splitter};
use drivebus_transport::{CanId, Frame};
use proptest::prelude::*;

fn any_frame() -> impl Strategy<Value = Frame> {
    let id =
        prop_oneof![(0u16..=0x7FF).prop_map(CanId::Standard), (0u32..=0x1FFF_FFFF).prop_map(CanId::Extended)];
    (id, proptest::collection::vec(any::<u8>(), 0..=8), any::<bool>(), 0u8..=8).prop_map(
        |(id, data, rtr, len)| {
            if rtr { Frame::try_remote(id, len).unwrap() } else { Frame::try_new(id, &data).unwrap() }
        },
    )
}

/// Bytes biased towards the protocols' alphabets so parsers get deep.
fn noisy_bytes() -> impl Strategy<Value = Vec<u8>> {
    let b = prop_oneof![
        any::<u8>(),
        proptest::sample::select(b"<> sendframe0123456789abcdefABCDEFtTrR\r\x07".to_vec()),
    ];
    proptest::collection::vec(b, 0..400)
}

proptest! {
    #[test]
    fn socketcand_stream_never_panics(data in noisy_bytes(), cuts in proptest::collection::vec(0usize..400, 0..6)) {
        let mut s = Splitter::new();
        let mut last = 0;
        let mut cuts = cuts;
        cuts.push(data.len());
        cuts.sort_unstable();
        for c in cuts {
            let c = c.min(data.len());
            if c >= last {
                s.feed(&data[last..c], |m| { let _ = proto::parse(m); });
                last = c;
            }
        }
    }

    #[test]
    fn socketcand_send_and_frame_round_trip(f in any_frame(), ts in 0u64..10_000_000_000_000_000, cut in 0usize..80) {
        prop_assume!(!f.is_rtr());
        let mut text = String::new();
        proto::write_send(&mut text, &f);
        proto::write_frame(&mut text, &f, ts);
        let bytes = text.as_bytes();
        let cut = cut.min(bytes.len());
        let mut got = Vec::new();
        let mut s = Splitter::new();
        s.feed(&bytes[..cut], |m| got.push(proto::parse(m).to_owned_msg()));
        s.feed(&bytes[cut..], |m| got.push(proto::parse(m).to_owned_msg()));
        prop_assert_eq!(got, vec![Owned::Send(f), Owned::Frame(f, ts)]);
    }

    #[test]
    fn slcan_lines_never_panic(data in noisy_bytes()) {
        let mut split = LineSplitter::new();
        let mut dev = SlcanDevice::new();
        let mut reply = Vec::new();
        split.feed(&data, |t| if let Token::Line(l) = t {
            let _ = slcan::parse_frame(l);
            dev.handle_line(l, &mut reply);
        });
        prop_assert!(reply.len() <= data.len() * 6 + 6);
    }

    #[test]
    fn slcan_round_trip(f in any_frame(), ts in proptest::option::of(0u16..60_000)) {
        let mut line = Vec::new();
        slcan::encode_stamped(&f, ts, &mut line);
        let mut got = Vec::new();
        LineSplitter::new().feed(&line, |t| if let Token::Line(l) = t { got.push(slcan::parse_frame(l)) });
        prop_assert_eq!(got, vec![Ok(f)]);
    }
}

#[derive(Debug, PartialEq)]
enum Owned {
    Send(Frame),
    Frame(Frame, u64),
    Other,
}

trait ToOwnedMsg {
    fn to_owned_msg(&self) -> Owned;
}

impl ToOwnedMsg for Message<'_> {
    fn to_owned_msg(&self) -> Owned {
        match self {
            Message::Send(f) => Owned::Send(*f),
            Message::Frame(f, t) => Owned::Frame(*f, *t),
            _ => Owned::Other,
        }
    }
}
