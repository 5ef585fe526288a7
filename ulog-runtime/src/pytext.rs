//! Numbers as Python (and numpy) print them, so that exports read like pyulog's output and
//! parse back to the exact stored value; and read them as Python's `int()` does.
//!
//! ```
//! use ulog_runtime::pytext::{f32_text, f64_text};
//! assert_eq!(f32_text(0.1), "0.1");          // numpy's str(np.float32(0.1))
//! assert_eq!(f64_text(f64::from(0.1f32)), "0.10000000149011612"); // Python's repr
//! assert_eq!(f64_text(1.5e-5), "1.5e-05");
//! ```

/// `x` as Python's `repr(float)`: shortest digits that round-trip (a tie to the even digit),
/// positional for `1e-4 <= |x| < 1e16`, else `1.5e-05` / `1e+16`.
pub fn f64_text(x: f64) -> String {
    special(x).unwrap_or_else(|| {
        let sci = tie_to_even(format!("{x:e}"), |t| t.parse::<f64>().ok() == Some(x), x);
        python_style(&sci, (1e-4..1e16).contains(&x.abs()))
    })
}

/// `x` as numpy prints a `float32`: the shortest digits that round-trip as `f32` (a tie to
/// the even digit), positional for `1e-4 <= |x| < 1e6`, else `4.2949675e+06`.
pub fn f32_text(x: f32) -> String {
    let wide = f64::from(x);
    special(wide).unwrap_or_else(|| {
        let sci = tie_to_even(format!("{x:e}"), |t| t.parse::<f32>().ok() == Some(x), wide);
        python_style(&sci, (1e-4..1e6).contains(&wide.abs()))
    })
}

/// When the exact value lies halfway between two shortest texts, Rust picks the upper one and
/// Python and numpy the one with an even last digit: pick that one.
fn tie_to_even(sci: String, round_trips: impl Fn(&str) -> bool, exact: f64) -> String {
    let (mantissa, exp) = sci.split_once('e').expect("`{:e}` has an exponent");
    let last = mantissa.as_bytes()[mantissa.len() - 1];
    if !mantissa.contains('.') || last % 2 == 0 || last == b'0' {
        return sci;
    }
    let lower = format!(
        "{}{}e{exp}",
        &mantissa[..mantissa.len() - 1],
        char::from(last - 1)
    );
    // Halfway: the exact value, written out, is the lower text followed by a 5 and zeros.
    let digits = mantissa.len() - mantissa.starts_with('-') as usize - 1;
    let exact_text = format!("{:.*e}", digits + 40, exact);
    let (exact_mantissa, _) = exact_text.split_once('e').expect("an exponent");
    let halfway = exact_mantissa.len() > mantissa.len()
        && exact_mantissa.starts_with(&lower[..mantissa.len()])
        && exact_mantissa[mantissa.len()..].trim_end_matches('0') == "5";
    if halfway && round_trips(&lower) {
        lower
    } else {
        sci
    }
}

fn special(x: f64) -> Option<String> {
    if x.is_nan() {
        Some("nan".into())
    } else if x.is_infinite() {
        Some(if x > 0.0 { "inf" } else { "-inf" }.into())
    } else if x == 0.0 {
        Some(if x.is_sign_negative() { "-0.0" } else { "0.0" }.into())
    } else {
        None
    }
}

/// Rewrites Rust's shortest `{:e}` form (`-1.5e-5`) in Python's style, positional or
/// scientific.
fn python_style(sci: &str, positional: bool) -> String {
    let (sign, rest) = match sci.strip_prefix('-') {
        Some(r) => ("-", r),
        None => ("", sci),
    };
    let (mantissa, exp) = rest.split_once('e').expect("`{:e}` has an exponent");
    let exp: i32 = exp.parse().expect("an integer exponent");
    let digits: String = mantissa.chars().filter(char::is_ascii_digit).collect();
    if positional {
        let body = if exp >= 0 {
            let int_len = (exp + 1) as usize;
            if digits.len() <= int_len {
                format!("{digits}{}.0", "0".repeat(int_len - digits.len()))
            } else {
                format!("{}.{}", &digits[..int_len], &digits[int_len..])
            }
        } else {
            format!("0.{}{digits}", "0".repeat((-exp - 1) as usize))
        };
        format!("{sign}{body}")
    } else {
        let mantissa = if digits.len() == 1 {
            digits
        } else {
            format!("{}.{}", &digits[..1], &digits[1..])
        };
        let exp_sign = if exp < 0 { '-' } else { '+' };
        format!("{sign}{mantissa}e{exp_sign}{:02}", exp.abs())
    }
}

/// Python's `int()` of a text: an optional sign, decimal digits (single underscores between
/// them; any Unicode decimal digit, as `int("٣")` is 3), surrounding whitespace (Unicode's,
/// which is what `int()` strips: not `\x1c` to `\x1f`, which `str.isspace` also counts);
/// `None` for anything else (or a number past `i128`).
pub(crate) fn python_int(text: &str) -> Option<i128> {
    let t = text.trim();
    let digits = t.strip_prefix(['+', '-']).unwrap_or(t);
    if digits.is_empty()
        || digits.starts_with('_')
        || digits.ends_with('_')
        || digits.contains("__")
    {
        return None;
    }
    let mut v: i128 = 0;
    for c in digits.chars().filter(|&c| c != '_') {
        v = v
            .checked_mul(10)?
            .checked_add(i128::from(decimal_digit(c)?))?;
    }
    Some(if t.starts_with('-') { -v } else { v })
}

/// The first of each run of ten Unicode decimal digits (general category `Nd`, zero to
/// nine in order), as Python 3.11's `unicodedata` (Unicode 14.0) lists them.
const DIGIT_ZEROS: [u32; 66] = [
    0x0030, 0x0660, 0x06F0, 0x07C0, 0x0966, 0x09E6, 0x0A66, 0x0AE6, 0x0B66, 0x0BE6, 0x0C66, 0x0CE6,
    0x0D66, 0x0DE6, 0x0E50, 0x0ED0, 0x0F20, 0x1040, 0x1090, 0x17E0, 0x1810, 0x1946, 0x19D0, 0x1A80,
    0x1A90, 0x1B50, 0x1BB0, 0x1C40, 0x1C50, 0xA620, 0xA8D0, 0xA900, 0xA9D0, 0xA9F0, 0xAA50, 0xABF0,
    0xFF10, 0x104A0, 0x10D30, 0x11066, 0x110F0, 0x11136, 0x111D0, 0x112F0, 0x11450, 0x114D0,
    0x11650, 0x116C0, 0x11730, 0x118E0, 0x11950, 0x11C50, 0x11D50, 0x11DA0, 0x16A60, 0x16AC0,
    0x16B50, 0x1D7CE, 0x1D7D8, 0x1D7E2, 0x1D7EC, 0x1D7F6, 0x1E140, 0x1E2F0, 0x1E950, 0x1FBF0,
];

/// The value of a Unicode decimal digit, as Python's `unicodedata.decimal`.
fn decimal_digit(c: char) -> Option<u8> {
    let c = u32::from(c);
    let zero = match DIGIT_ZEROS.binary_search(&c) {
        Ok(i) => DIGIT_ZEROS[i],
        Err(0) => return None,
        Err(i) => DIGIT_ZEROS[i - 1],
    };
    u8::try_from(c - zero).ok().filter(|&d| d < 10)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integers_read_as_pythons_int_reads_them() {
        // What Python 3 says: int(" +1_000 ") == 1000, int("-7") == -7; the rest ValueError.
        assert_eq!(python_int(" +1_000 \n"), Some(1000));
        assert_eq!(python_int("-7"), Some(-7));
        assert_eq!(python_int("007"), Some(7));
        for bad in [
            "", "-", "_1", "1_", "1__0", "1.0", "0x10", "+-1", "1 2", "²", "Ⅻ", "½",
        ] {
            assert_eq!(python_int(bad), None, "{bad:?}");
        }
        // int("٣") == 3, int("१०") == 10, int("\x857\u3000") == 7, int("1_٣") == 13; int("\x1c7")
        // is a ValueError.
        assert_eq!(python_int("٣"), Some(3));
        assert_eq!(python_int("१०"), Some(10));
        assert_eq!(python_int("\u{85}7\u{3000}"), Some(7));
        assert_eq!(python_int("\x1c7"), None);
        assert_eq!(python_int("1_٣"), Some(13));
        assert_eq!(python_int("-𝟗"), Some(-9));
    }

    #[test]
    fn like_python_and_numpy() {
        // Expected texts are Python's repr / numpy's str of the same values.
        for (x, text) in [
            (0.05000000074505806, "0.05000000074505806"),
            (-1.0, "-1.0"),
            (1e20, "1e+20"),
            (1.5e-5, "1.5e-05"),
            (123456.0, "123456.0"),
            (0.0001, "0.0001"),
            (1e16, "1e+16"),
            (9999999999999998.0, "9999999999999998.0"),
        ] {
            assert_eq!(f64_text(x), text);
        }
        for (x, text) in [
            (0.1f32, "0.1"),
            (16.2, "16.2"),
            (1e-5, "1e-05"),
            (3.4028235e38, "3.4028235e+38"),
        ] {
            assert_eq!(f32_text(x), text);
        }
        assert_eq!(f32_text(-0.0), "-0.0");
        assert_eq!(f32_text(f32::NAN), "nan");
        assert_eq!(f64_text(f64::NEG_INFINITY), "-inf");
    }

    #[test]
    fn texts_parse_back_exactly() {
        let mut x = 1.234_567_9e-7_f32;
        for _ in 0..200 {
            assert_eq!(f32_text(x).parse::<f32>().unwrap().to_bits(), x.to_bits());
            let y = f64::from(x) * 1.000_000_1;
            assert_eq!(f64_text(y).parse::<f64>().unwrap().to_bits(), y.to_bits());
            x *= -3.7;
        }
    }
}
