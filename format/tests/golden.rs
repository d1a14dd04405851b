//! The writer's output for the SPEC.md Appendix D example is exactly the hexdump printed there.

use hce_format::{example, read, validate_bytes, write};

/// `hexdump -C` layout: offset, 16 bytes in two groups of 8, ASCII; repeated lines become `*`.
fn hexdump(bytes: &[u8]) -> String {
    let mut out = String::new();
    let mut previous: Option<&[u8]> = None;
    let mut starred = false;
    for (i, line) in bytes.chunks(16).enumerate() {
        if previous == Some(line) && line.len() == 16 {
            if !starred {
                out.push_str("*\n");
                starred = true;
            }
            continue;
        }
        starred = false;
        previous = Some(line);
        let mut hex = String::new();
        for (k, b) in line.iter().enumerate() {
            if k == 8 {
                hex.push(' ');
            }
            hex.push_str(&format!("{b:02x} "));
        }
        let ascii: String = line
            .iter()
            .map(|&b| {
                if (0x20..0x7f).contains(&b) {
                    b as char
                } else {
                    '.'
                }
            })
            .collect();
        out.push_str(&format!("{:08x}  {hex:<49} |{ascii}|\n", i * 16));
    }
    out.push_str(&format!("{:08x}\n", bytes.len()));
    out
}

/// The hexdump block of SPEC.md Appendix D, between the first ``` fence after its heading.
fn spec_hexdump() -> String {
    let spec = include_str!("../../SPEC.md");
    let appendix = spec
        .split("## Appendix D")
        .nth(1)
        .expect("SPEC.md has an Appendix D");
    let block = appendix
        .split("```text\n")
        .nth(1)
        .expect("Appendix D has a ```text block");
    block.split("```").next().unwrap_or_default().to_string()
}

#[test]
fn writer_matches_the_spec_hexdump() {
    let bytes = write(&example::single_triangle()).unwrap();
    let dump = hexdump(&bytes);
    if std::env::var_os("HCE_PRINT_GOLDEN").is_some() {
        print!("{dump}");
    }
    assert_eq!(
        dump,
        spec_hexdump(),
        "regenerate with HCE_PRINT_GOLDEN=1 cargo test -p hce-format --test golden -- --nocapture"
    );
}

#[test]
fn example_is_valid_and_round_trips() {
    let c = example::single_triangle();
    let bytes = write(&c).unwrap();
    assert_eq!(validate_bytes(&bytes), vec![]);
    assert_eq!(read(&bytes).unwrap(), c);
    assert_eq!(bytes.len(), 256 * 16 + 4 * 9);
}
