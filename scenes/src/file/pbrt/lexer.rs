//! Splits pbrt's scene format into tokens with their lines, and groups a directive's
//! parameter list (`"type name" [ values ]`).

/// One token of a pbrt file.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Token {
    /// A bare word: a directive name, or `true`/`false`.
    Word(String),
    /// A number, kept as written so that it can be parsed as `f32` exactly.
    Number(String),
    /// A quoted string, without its quotes.
    Str(String),
    Open,
    Close,
}

/// Tokens with their (1-based) lines; the error names the line of an unterminated string.
pub(super) fn tokenize(text: &str) -> Result<Vec<(Token, u32)>, (u32, String)> {
    let mut tokens = Vec::new();
    let mut line = 1u32;
    let mut chars = text.chars().peekable();
    while let Some(&c) = chars.peek() {
        match c {
            '\n' => {
                line += 1;
                chars.next();
            }
            c if c.is_whitespace() => {
                chars.next();
            }
            '#' => {
                while chars.peek().is_some_and(|&c| c != '\n') {
                    chars.next();
                }
            }
            '[' => {
                chars.next();
                tokens.push((Token::Open, line));
            }
            ']' => {
                chars.next();
                tokens.push((Token::Close, line));
            }
            '"' => {
                chars.next();
                let mut s = String::new();
                loop {
                    match chars.next() {
                        Some('"') => break,
                        Some('\n') | None => return Err((line, "a string is not closed".into())),
                        Some(c) => s.push(c),
                    }
                }
                tokens.push((Token::Str(s), line));
            }
            _ => {
                let mut s = String::new();
                while let Some(&c) = chars.peek() {
                    if c.is_whitespace() || matches!(c, '[' | ']' | '"' | '#') {
                        break;
                    }
                    s.push(c);
                    chars.next();
                }
                let number =
                    s.starts_with(|c: char| c.is_ascii_digit() || matches!(c, '-' | '+' | '.'));
                tokens.push((
                    if number {
                        Token::Number(s)
                    } else {
                        Token::Word(s)
                    },
                    line,
                ));
            }
        }
    }
    Ok(tokens)
}

/// A parameter of a directive: `"float fov" [ 45 ]`.
#[derive(Clone, Debug)]
pub(super) struct Param {
    /// The declared type: `float`, `rgb`, `string`, ...
    pub ty: String,
    /// The parameter's name.
    pub name: String,
    /// Its values as written (numbers, strings, or `true`/`false`).
    pub values: Vec<Token>,
    /// Line it starts on.
    pub line: u32,
}
