# usd-core's pxr modules fill themselves in at import (Tf.PreparePythonModule from the C++
# library) and ship no stubs: to the type checker every name in them is Any.
