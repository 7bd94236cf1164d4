//! Just enough JSON to read `scripts/mitsuba_scene_params.py`'s output (the project has no
//! JSON dependency, and a test adds none): objects, arrays, numbers, strings, booleans and
//! null, with the escapes Python's `json` writes.

#[derive(Clone, Debug, PartialEq)]
pub enum Json {
    Null,
    Bool(bool),
    Number(f64),
    String(String),
    Array(Vec<Json>),
    /// Keys in the file's order.
    Object(Vec<(String, Json)>),
}

impl Json {
    pub fn parse(text: &str) -> Result<Json, String> {
        let mut p = Parser {
            text: text.as_bytes(),
            at: 0,
        };
        let value = p.value()?;
        p.space();
        match p.at == p.text.len() {
            true => Ok(value),
            false => Err(format!("text after the value at byte {}", p.at)),
        }
    }

    /// The member `key` of an object; panics naming the key when there is none.
    pub fn get(&self, key: &str) -> &Json {
        self.member(key)
            .unwrap_or_else(|| panic!("no \"{key}\" in {self:?}"))
    }

    pub fn member(&self, key: &str) -> Option<&Json> {
        match self {
            Json::Object(members) => members.iter().find(|(k, _)| k == key).map(|(_, v)| v),
            _ => None,
        }
    }

    pub fn members(&self) -> &[(String, Json)] {
        match self {
            Json::Object(members) => members,
            other => panic!("expected an object, found {other:?}"),
        }
    }

    pub fn items(&self) -> &[Json] {
        match self {
            Json::Array(items) => items,
            other => panic!("expected an array, found {other:?}"),
        }
    }

    pub fn number(&self) -> f64 {
        match self {
            Json::Number(x) => *x,
            other => panic!("expected a number, found {other:?}"),
        }
    }

    pub fn string(&self) -> &str {
        match self {
            Json::String(s) => s,
            other => panic!("expected a string, found {other:?}"),
        }
    }

    /// An array of numbers.
    pub fn numbers(&self) -> Vec<f64> {
        self.items().iter().map(Json::number).collect()
    }
}

struct Parser<'a> {
    text: &'a [u8],
    at: usize,
}

impl Parser<'_> {
    fn space(&mut self) {
        while self.text.get(self.at).is_some_and(u8::is_ascii_whitespace) {
            self.at += 1;
        }
    }

    fn next(&mut self) -> Result<u8, String> {
        let c = *self.text.get(self.at).ok_or("unexpected end")?;
        self.at += 1;
        Ok(c)
    }

    fn expect(&mut self, word: &str) -> Result<(), String> {
        match self.text[self.at..].starts_with(word.as_bytes()) {
            true => {
                self.at += word.len();
                Ok(())
            }
            false => Err(format!("expected {word} at byte {}", self.at)),
        }
    }

    fn value(&mut self) -> Result<Json, String> {
        self.space();
        match self.text.get(self.at).ok_or("unexpected end")? {
            b'{' => self
                .sequence(b'}', |p| {
                    let key = match p.value()? {
                        Json::String(key) => key,
                        other => return Err(format!("a key that is not a string: {other:?}")),
                    };
                    p.space();
                    p.expect(":")?;
                    Ok((key, p.value()?))
                })
                .map(Json::Object),
            b'[' => self.sequence(b']', Parser::value).map(Json::Array),
            b'"' => self.string().map(Json::String),
            b'n' => self.expect("null").map(|_| Json::Null),
            b't' => self.expect("true").map(|_| Json::Bool(true)),
            b'f' => self.expect("false").map(|_| Json::Bool(false)),
            _ => self.number(),
        }
    }

    /// The items of an array or object, from its opening bracket to `close`.
    fn sequence<T>(
        &mut self,
        close: u8,
        mut item: impl FnMut(&mut Self) -> Result<T, String>,
    ) -> Result<Vec<T>, String> {
        self.at += 1;
        let mut items = Vec::new();
        self.space();
        if self.text.get(self.at) == Some(&close) {
            self.at += 1;
            return Ok(items);
        }
        loop {
            items.push(item(self)?);
            self.space();
            match self.next()? {
                b',' => {}
                c if c == close => return Ok(items),
                c => return Err(format!("unexpected '{}' at byte {}", c as char, self.at)),
            }
        }
    }

    fn string(&mut self) -> Result<String, String> {
        self.at += 1;
        let mut s = String::new();
        loop {
            let start = self.at;
            while !matches!(self.text.get(self.at), Some(b'"' | b'\\') | None) {
                self.at += 1;
            }
            s.push_str(std::str::from_utf8(&self.text[start..self.at]).map_err(|e| e.to_string())?);
            match self.next()? {
                b'"' => return Ok(s),
                _ => s.push(match self.next()? {
                    b'n' => '\n',
                    b't' => '\t',
                    b'r' => '\r',
                    b'b' => '\u{8}',
                    b'f' => '\u{c}',
                    b'u' => {
                        let hex = self.text.get(self.at..self.at + 4).ok_or("short \\u")?;
                        self.at += 4;
                        let code = u32::from_str_radix(std::str::from_utf8(hex).unwrap_or("?"), 16)
                            .map_err(|e| e.to_string())?;
                        char::from_u32(code).unwrap_or(char::REPLACEMENT_CHARACTER)
                    }
                    c => c as char,
                }),
            }
        }
    }

    fn number(&mut self) -> Result<Json, String> {
        let start = self.at;
        while self
            .text
            .get(self.at)
            .is_some_and(|c| c.is_ascii_digit() || b"+-.eE".contains(c))
        {
            self.at += 1;
        }
        let word = std::str::from_utf8(&self.text[start..self.at]).unwrap_or("");
        word.parse()
            .map(Json::Number)
            .map_err(|_| format!("not a value at byte {start}: \"{word}\""))
    }
}
