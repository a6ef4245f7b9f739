"""The linearised dynamics about the static state, the pantograph, Newmark and the passage backends."""
