//! The JSON-lines files of a run directory (`rollouts.jsonl`, `predictions.jsonl`, ...), read
//! as their writer may leave them: a run appends one line per record and can be stopped in
//! the middle of one.

use serde_json::Value;

/// One parsed line.
#[derive(Debug)]
pub struct JsonLine<'a> {
    /// 1-based line number in the file.
    pub number: usize,
    /// The line as written (kept, so that a file rewritten from it keeps its bytes).
    pub text: &'a str,
    /// Its value.
    pub value: Value,
}

/// The complete lines of a JSON-lines text.
#[derive(Debug)]
pub struct JsonLines<'a> {
    /// Every non-blank line that parsed, in order.
    pub lines: Vec<JsonLine<'a>>,
    /// The number of a last line cut off mid-write (it does not parse and has no newline
    /// after it), left out of `lines`.
    pub torn: Option<usize>,
}

/// A line that does not parse and is not a cut-off last line: the file is corrupt there.
#[derive(Debug)]
pub struct JsonLineError {
    /// 1-based line number.
    pub line: usize,
    /// What serde_json found.
    pub error: serde_json::Error,
}

/// Parses `text` line by line, blank lines skipped. A last line that does not parse and is not
/// followed by a newline is the record being written when the run stopped: reported in
/// [`JsonLines::torn`], not an error. Any other line that does not parse is an error.
pub fn parse_json_lines(text: &str) -> Result<JsonLines<'_>, JsonLineError> {
    let numbered: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| (i + 1, l))
        .collect();
    let mut lines = Vec::with_capacity(numbered.len());
    let mut torn = None;
    for (k, &(number, line)) in numbered.iter().enumerate() {
        match serde_json::from_str(line) {
            Ok(value) => lines.push(JsonLine {
                number,
                text: line,
                value,
            }),
            Err(_) if k + 1 == numbered.len() && !text.ends_with('\n') => torn = Some(number),
            Err(error) => {
                return Err(JsonLineError {
                    line: number,
                    error,
                })
            }
        }
    }
    Ok(JsonLines { lines, torn })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cut_off_last_line_is_torn_and_any_other_bad_line_an_error() {
        let whole = "{\"episode\":0}\n\n{\"episode\":1}\n";
        let read = parse_json_lines(whole).unwrap();
        assert_eq!(read.torn, None);
        let numbers: Vec<usize> = read.lines.iter().map(|l| l.number).collect();
        assert_eq!(numbers, [1, 3]);
        assert_eq!(read.lines[1].text, "{\"episode\":1}");
        assert_eq!(read.lines[1].value["episode"], 1);

        let cut = format!("{whole}{{\"episode\":2,\"co");
        let read = parse_json_lines(&cut).unwrap();
        assert_eq!(read.torn, Some(4));
        assert_eq!(read.lines.len(), 2);

        // Ended by a newline, the same line was written whole and is corrupt.
        let corrupt = format!("{cut}\n");
        assert_eq!(parse_json_lines(&corrupt).unwrap_err().line, 4);
        let middle = "{\"episode\":0}\n{\"epi\n{\"episode\":1}";
        assert_eq!(parse_json_lines(middle).unwrap_err().line, 2);
        // A last line that parses needs no newline.
        assert_eq!(parse_json_lines("{\"episode\":0}").unwrap().lines.len(), 1);
    }
}
