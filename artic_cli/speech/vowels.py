"""The vowels speech is judged against."""

# male Japanese vowel averages (F1, F2 Hz; ../shared/reference/acoustics.md, Jo Chul-Ho's thesis, Table 4.3)
JAPANESE_VOWELS = {"a": (753.0, 1385.0), "i": (315.0, 2172.0), "u": (367.0, 1332.0), "e": (500.0, 1947.0),
                   "o": (520.0, 997.0)}
