"""Speech from targets in time: utterances (:mod:`.utterance`), the plan that solves each segment's target
(:mod:`.plan`), the force course (:mod:`.course`), the sources' controls and the sound (:mod:`.speak`), and
what a spoken utterance did, measured (:mod:`.measures`)."""
