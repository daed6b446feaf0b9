"""Acoustics: from an area function (a tube, glottis to lips) to transfer functions, formants and sound."""
