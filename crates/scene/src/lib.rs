//! haze's scene: the model the integrators read, and the Mitsuba 3 XML loader that builds it.
