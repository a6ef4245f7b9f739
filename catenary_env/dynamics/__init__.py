"""The linearised dynamics about the static state, the pantograph, Newmark, and the two dynamic models
(``exact/``, ``span_modes/``) behind one passage protocol (:mod:`.protocol`, the table :mod:`.models`)."""
