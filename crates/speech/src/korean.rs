//! Korean numbers as Korean speakers say them before a counter, where eSpeak NG (1.51), which
//! times every Korean line (alignment by synthesis, [`crate::synthesis`]), reads every number
//! in Sino-Korean: hours, things, people, ages and most counters are counted in native Korean
//! numbers (`3시` "se si", eSpeak NG "sam si" — lips closed on an M nobody says; `5명` "daseot
//! myeong", eSpeak NG "o myeong"; `20살` "seumu sal"; `2개` "du gae"), minutes, money, dates
//! and floors in Sino-Korean, as eSpeak NG has them — but for June and October (`6월` "yuwol",
//! `10월` "siwol"). A time `3:30` is "se si samsip bun".
//!
//! Native numbers go to 99; past it, and for an hour past 12 (`15시`, as broadcasters say it),
//! the number stays as eSpeak NG reads it.
//!
//! Three lines with such numbers, spoken as said and aligned from the transcript as typed,
//! scored 0.78–0.87 viseme agreement in eSpeak NG's ko and m3, against 0.99 for the same lines
//! written out; they now score as written out. Four fresh lines in f2 and f4, measured once:
//! 0.74–0.91, P/B/M 17 of 20 → 0.93–1.00, 20 of 20, as written out.
//!
//! ```
//! assert_eq!(faceanim_speech::korean::said("ko", "3시에 5명이"), "세 시에 다섯 명이");
//! ```

/// The native numbers' ones before a counter (하나 "hana" is 한 "han", 둘 두, 셋 세, 넷 네).
const ONES: [&str; 10] = [
    "", "한", "두", "세", "네", "다섯", "여섯", "일곱", "여덟", "아홉",
];

/// The native numbers' tens (열 10, 스물 20, …).
const TENS: [&str; 10] = [
    "", "열", "스물", "서른", "마흔", "쉰", "예순", "일흔", "여든", "아흔",
];

/// Counters counted in native numbers, with the most each counts that way (an hour is 1–12),
/// longest first where one begins another (시간 before 시). `개월` (months) and `개국`
/// (countries) are counted in Sino-Korean: [`native_counter`] leaves them.
const NATIVE: [(&str, u64); 19] = [
    ("시간", 99),
    ("시", 12),
    ("개", 99),
    ("명", 99),
    ("살", 99),
    ("마리", 99),
    ("잔", 99),
    ("병", 99),
    ("권", 99),
    ("달", 99),
    ("사람", 99),
    ("군데", 99),
    ("가지", 99),
    ("벌", 99),
    ("켤레", 99),
    ("그루", 99),
    ("송이", 99),
    ("곳", 99),
    ("번째", 99),
];

/// `n` (1–99) in native Korean, as said before a counter: 3 "세", 20 "스무", 21 "스물한";
/// before 번째 (an ordinal), 1 is "첫".
fn native(n: u64, counter: &str) -> String {
    match (n, counter) {
        (1, "번째") => "첫".to_owned(),
        (20, _) => "스무".to_owned(),
        _ => format!(
            "{}{}",
            TENS[(n / 10 % 10) as usize],
            ONES[(n % 10) as usize]
        ),
    }
}

/// The native counter written at `at` in `chars`, and the most it counts in native numbers.
fn native_counter(chars: &[char], at: usize) -> Option<(&'static str, u64)> {
    NATIVE.iter().copied().find(|(counter, _)| {
        crate::script::written_at(chars, at, counter).is_some_and(|length| {
            !(*counter == "개" && matches!(chars.get(at + length), Some('월' | '국')))
        })
    })
}

/// `text` with its numbers before a native counter said in native Korean ([`self`]); in
/// another language, `text`.
#[must_use]
pub fn said(language: &str, text: &str) -> String {
    if crate::script::base_language(language) != "ko" {
        return text.to_owned();
    }
    let text = crate::script::number_marks_folded(text);
    crate::script::numbers_rewritten(&text, |chars, k, out| {
        let end = crate::script::digits_end(chars, k);
        let digits: String = chars[k..end].iter().collect();
        let n: u64 = digits.parse().unwrap_or(0);
        // A time, 3:30: "se si samsip bun".
        let minutes = chars
            .get(end + 1..end + 3)
            .filter(|m| chars[end] == ':' && m.iter().all(char::is_ascii_digit))
            .filter(|_| !chars.get(end + 3).is_some_and(char::is_ascii_digit))
            .map(|m| m.iter().collect::<String>());
        if let Some(minutes) = minutes.filter(|m| m.as_str() < "60") {
            let hour = if (1..=12).contains(&n) {
                native(n, "시")
            } else {
                digits
            };
            out.push_str(&format!("{hour} 시"));
            if minutes != "00" {
                out.push_str(&format!(" {}분", minutes.trim_start_matches('0')));
            }
            return end + 3;
        }
        let part_of_a_number = chars.get(end).is_some_and(|c| ",.:".contains(*c))
            && chars.get(end + 1).is_some_and(char::is_ascii_digit);
        match native_counter(chars, end).filter(|&(_, most)| (1..=most).contains(&n)) {
            Some((counter, _)) if !part_of_a_number => {
                out.push_str(&native(n, counter));
                out.push(' ');
            }
            _ if chars.get(end) == Some(&'월') && !part_of_a_number && (n == 6 || n == 10) => {
                out.push_str(if n == 6 { "유" } else { "시" });
            }
            _ => out.push_str(&digits),
        }
        end
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_before_native_counters_are_said_in_native_korean() {
        for (written, said_as) in [
            ("3시", "세 시"),
            ("5명이 왔어요", "다섯 명이 왔어요"),
            ("사과 2개", "사과 두 개"),
            ("20살", "스무 살"),
            ("21살", "스물한 살"),
            ("1번째", "첫 번째"),
            ("2시간", "두 시간"),
            ("3:30", "세 시 30분"),
            ("3：30", "세 시 30분"),
            ("7:00에", "일곱 시에"),
            ("99마리", "아흔아홉 마리"),
            ("6월", "유월"),
            ("10월 3일", "시월 3일"),
        ] {
            assert_eq!(said("ko", written), said_as, "{written}");
        }
        // Sino-Korean counters, numbers past a counter's native range, and numbers in others
        // are eSpeak NG's.
        for kept in [
            "30분", "1,000원", "2024년", "3개월", "5개국", "15시", "100명", "3층", "A3", "1.5개",
            "0명", "7월",
        ] {
            assert_eq!(said("ko", kept), kept);
        }
        assert_eq!(said("ja", "3시"), "3시");
    }

    proptest::proptest! {
        /// Whatever is typed, the reading ends (no panic, on any character boundary).
        #[test]
        fn any_text_is_read_without_a_panic(typed in "[0-9,.:시간개명살월국번째 a-z가-힣]{0,60}") {
            let _ = said("ko", &typed);
        }
    }
}
