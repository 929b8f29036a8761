//! Words the pronouncing dictionary lacks, pronounced as eSpeak NG says them.
//!
//! The recogniser aligns an English transcript phone by phone from the CMU pronouncing
//! dictionary; a word it lacks — a character's name, a number written in digits, a brand, a
//! new word — used to send the whole line to alignment by synthesis, which times a natural
//! voice less closely than the recogniser does (flite's slt: 0.88 against 0.96 agreement).
//! eSpeak NG pronounces any written English (its rules and its own dictionary, digits read as
//! numbers): its phones, in IPA, become the recogniser's ARPAbet here.

/// eSpeak NG's phones (IPA, stress marks removed) and the ARPAbet phones each is, in order:
/// `said … : phones …`, entries parted by `;`. The American flap (`ɾ`, a T or a D
/// between vowels) is the recogniser's T, which fits it.
const ARPABET: &str = "\
p : P ; b : B ; t ʔ : T ; d : D ; ɾ : T ; k x : K ; ɡ g : G ; m m̩ : M ; n n̩ : N ; ŋ : NG ;\
f : F ; v : V ; θ : TH ; ð : DH ; s : S ; z : Z ; ʃ : SH ; ʒ : ZH ; h : HH ; tʃ : CH ;\
dʒ : JH ; l l̩ ɫ ɬ : L ; ɹ r : R ; j : Y ; w ʍ : W ; ɑː ɑ ɒ a aː : AA ; æ : AE ;\
ʌ ə ɐ : AH ; ɔː ɔ : AO ; aʊ : AW ; aɪ : AY ; ɛ e : EH ; ɜː ɜ ɚ ɝ : ER ; eɪ : EY ;\
ɪ ᵻ ɨ : IH ; iː i : IY ; oʊ o oː əʊ : OW ; ɔɪ : OY ; ʊ : UH ; uː u : UW ; ɑːɹ ɑɹ : AA R ;\
ɔːɹ oːɹ ɔɹ oɹ : AO R ; ɛɹ eɹ ɛə : EH R ; ɪɹ iɹ ɪə iə : IH R ; ʊɹ ʊə : UH R ;\
aɪɚ aɪə : AY ER ; aʊɚ aʊə : AW ER ; əl : AH L";

/// The ARPAbet phones of an eSpeak NG phone ([`ARPABET`]).
fn arpabet(ipa: &str) -> Option<Vec<&'static str>> {
    ARPABET.split(';').find_map(|entry| {
        let (said, phones) = entry.split_once(':')?;
        said.split_whitespace()
            .any(|s| s == ipa)
            .then(|| phones.split_whitespace().collect())
    })
}

/// `word` (written English: a name, digits) in ARPAbet as eSpeak NG's US English says it;
/// `None` where eSpeak NG is not installed or says a phone the table above does not know.
#[must_use]
pub fn english(word: &str) -> Option<Vec<String>> {
    let spoken = faceanim_espeak_sys::speak(word, "en-us", None).ok()?;
    let mut phones = Vec::new();
    for phone in &spoken.phones {
        if phone.ipa == faceanim_espeak_sys::PAUSE {
            continue;
        }
        let bare: String = phone
            .ipa
            .chars()
            .filter(|c| !matches!(c, 'ˈ' | 'ˌ'))
            .collect();
        phones.extend(arpabet(&bare)?.into_iter().map(str::to_owned));
    }
    (!phones.is_empty()).then_some(phones)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_numbers_are_said_in_the_recognisers_phones() {
        if !faceanim_espeak_sys::available() {
            assert_eq!(english("Aelthas"), None);
            return;
        }
        // A word the dictionary has comes out as it writes it.
        assert_eq!(english("map").unwrap(), ["M", "AE", "P"]);
        let number = english("42").unwrap();
        assert!(
            number.starts_with(&["F".to_owned(), "AO".to_owned(), "R".to_owned()]),
            "{number:?}"
        );
        let name = english("Aelthas").unwrap();
        assert!(name.contains(&"TH".to_owned()), "{name:?}");
        assert!(
            name.last().is_some_and(|p| p == "S" || p == "Z"),
            "{name:?}"
        );
    }

    #[test]
    fn every_english_phone_of_espeak_ng_has_its_arpabet() {
        // The phones eSpeak NG's US English says, as its phoneme table names them.
        for ipa in [
            "p", "b", "t", "d", "ɾ", "k", "ɡ", "m", "n", "ŋ", "f", "v", "θ", "ð", "s", "z", "ʃ",
            "ʒ", "h", "tʃ", "dʒ", "l", "ɹ", "j", "w", "ɑː", "æ", "ʌ", "ə", "ɐ", "ɔː", "aʊ", "aɪ",
            "ɛ", "ɜː", "ɚ", "eɪ", "ɪ", "ᵻ", "iː", "i", "oʊ", "ɔɪ", "ʊ", "uː", "ɑːɹ", "ɔːɹ", "oːɹ",
            "ɛɹ", "ɪɹ", "ʊɹ", "aɪɚ", "aʊɚ", "əl",
        ] {
            assert!(arpabet(ipa).is_some(), "{ipa}");
        }
        assert_eq!(arpabet("ʁ"), None);
        // Entries either side of the table's line breaks stay apart.
        assert_eq!(arpabet("ŋ").unwrap(), ["NG"]);
        assert_eq!(arpabet("f").unwrap(), ["F"]);
        assert_eq!(arpabet("əl").unwrap(), ["AH", "L"]);
        assert_eq!(arpabet("ɑːɹ").unwrap(), ["AA", "R"]);
    }
}
