//! Open Sound Control 1.0 messages and bundles, as bytes (what the VMC protocol rides on).
//! Hand-written: the encoding is a few padding rules, and the crates that do it bring a decoder
//! and network layers the sender does not need.

/// One OSC argument.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Arg<'a> {
    Int(i32),
    Float(f32),
    Str(&'a str),
}

/// Appends `s` as an OSC string: its bytes, a NUL, padded with NULs to a multiple of 4.
fn push_str(out: &mut Vec<u8>, s: &str) {
    out.extend_from_slice(s.as_bytes());
    out.push(0);
    while !out.len().is_multiple_of(4) {
        out.push(0);
    }
}

/// One message: the address, the type tags, the arguments (big-endian).
pub(crate) fn message(address: &str, args: &[Arg<'_>]) -> Vec<u8> {
    let mut out = Vec::with_capacity(64);
    push_str(&mut out, address);
    let tags: String = std::iter::once(',')
        .chain(args.iter().map(|a| match a {
            Arg::Int(_) => 'i',
            Arg::Float(_) => 'f',
            Arg::Str(_) => 's',
        }))
        .collect();
    push_str(&mut out, &tags);
    for a in args {
        match a {
            Arg::Int(v) => out.extend_from_slice(&v.to_be_bytes()),
            Arg::Float(v) => out.extend_from_slice(&v.to_be_bytes()),
            Arg::Str(s) => push_str(&mut out, s),
        }
    }
    out
}

/// A bundle of `messages`, to be applied at once (time tag 1: "immediately").
pub(crate) fn bundle<'a>(messages: impl IntoIterator<Item = &'a [u8]>) -> Vec<u8> {
    let mut out = Vec::with_capacity(1024);
    push_str(&mut out, "#bundle");
    out.extend_from_slice(&1u64.to_be_bytes());
    for m in messages {
        out.extend_from_slice(&(m.len() as i32).to_be_bytes());
        out.extend_from_slice(m);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The OSC 1.0 specification's own example: `/oscillator/4/frequency` with the float
    /// 440.0.
    #[test]
    fn the_specifications_example_message() {
        let m = message("/oscillator/4/frequency", &[Arg::Float(440.0)]);
        let expected: Vec<u8> = [
            b"/oscillator/4/frequency\0".as_slice(),
            b",f\0\0",
            &[0x43, 0xdc, 0x00, 0x00],
        ]
        .concat();
        assert_eq!(m, expected);
    }

    #[test]
    fn strings_are_padded_and_bundles_carry_their_sizes() {
        let m = message("/a", &[Arg::Str("abc"), Arg::Int(1)]);
        assert_eq!(m, b"/a\0\0,si\0abc\0\0\0\0\x01");
        let b = bundle([m.as_slice()]);
        assert_eq!(&b[..8], b"#bundle\0");
        assert_eq!(&b[8..16], &1u64.to_be_bytes());
        assert_eq!(&b[16..20], &(m.len() as i32).to_be_bytes());
        assert_eq!(&b[20..], m.as_slice());
    }
}
